#include "semslam/geometry/rigid3.h"

#include <fmt/format.h>

#include <Eigen/SVD>
#include <cmath>

namespace semslam {
namespace {

Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
  if (r.determinant() < 0) {
    Eigen::Matrix3d u = svd.matrixU();
    u.col(2) *= -1.0;
    r = u * svd.matrixV().transpose();
  }
  return r;
}

// Left Jacobian of SO(3) and its inverse, for the SE(3) exponential and logarithm.
Eigen::Matrix3d LeftJacobian(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  const Eigen::Matrix3d w = SkewSymmetric(phi);
  if (theta < 1e-8) return Eigen::Matrix3d::Identity() + 0.5 * w;
  const double t2 = theta * theta;
  return Eigen::Matrix3d::Identity() + (1.0 - std::cos(theta)) / t2 * w + (theta - std::sin(theta)) / (t2 * theta) * w * w;
}

Eigen::Matrix3d LeftJacobianInverse(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  const Eigen::Matrix3d w = SkewSymmetric(phi);
  if (theta < 1e-8) return Eigen::Matrix3d::Identity() - 0.5 * w;
  const double half = 0.5 * theta;
  const double coeff = (1.0 - half * std::cos(half) / std::sin(half)) / (theta * theta);
  return Eigen::Matrix3d::Identity() - 0.5 * w + coeff * w * w;
}

}  // namespace

Rigid3d::Rigid3d(const Eigen::Matrix3d& r, const Eigen::Vector3d& t)
    : rotation(Eigen::Quaterniond(r).normalized()), translation(t) {}

Rigid3d Rigid3d::FromMatrix(const Eigen::Matrix3x4d& matrix) {
  return Rigid3d(NearestRotation(matrix.leftCols<3>()), matrix.col(3));
}

Eigen::Matrix3x4d Rigid3d::ToMatrix() const {
  Eigen::Matrix3x4d m;
  m.leftCols<3>() = rotation.toRotationMatrix();
  m.col(3) = translation;
  return m;
}

Eigen::Matrix4d Rigid3d::ToMatrix4() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topRows<3>() = ToMatrix();
  return m;
}

Rigid3d Rigid3d::Inverse() const {
  const Eigen::Quaterniond inv = rotation.conjugate();
  return Rigid3d(inv, -(inv * translation));
}

Rigid3d Rigid3d::operator*(const Rigid3d& other) const {
  return Rigid3d(rotation * other.rotation, rotation * other.translation + translation);
}

Rigid3d Rigid3d::Exp(const Eigen::Vector6d& twist) {
  const Eigen::Vector3d rho = twist.head<3>();
  const Eigen::Vector3d phi = twist.tail<3>();
  return Rigid3d(QuaternionExp(phi), LeftJacobian(phi) * rho);
}

Eigen::Vector6d Rigid3d::Log() const {
  const Eigen::Vector3d phi = QuaternionLog(rotation);
  Eigen::Vector6d twist;
  twist.head<3>() = LeftJacobianInverse(phi) * translation;
  twist.tail<3>() = phi;
  return twist;
}

double Rigid3d::RotationAngle() const { return QuaternionLog(rotation).norm(); }

double OrthonormalityDeviation(const Eigen::Matrix3d& r) {
  return (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
}

std::optional<std::string> RotationDefect(const Eigen::Matrix3d& r, double tolerance) {
  const double deviation = OrthonormalityDeviation(r);
  if (!(deviation <= tolerance))
    return fmt::format("not orthonormal (largest |R^T R - I| entry {:.3g})", deviation);
  if (!(r.determinant() > 0.0)) return std::string("a reflection (determinant -1)");
  return std::nullopt;
}

bool IsRotation(const Eigen::Matrix3d& r, double tolerance) { return !RotationDefect(r, tolerance); }

Eigen::Matrix3d SkewSymmetric(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Quaterniond QuaternionExp(const Eigen::Vector3d& rotation_vector) {
  const double theta = rotation_vector.norm();
  if (theta < 1e-10) {
    return Eigen::Quaterniond(1.0, 0.5 * rotation_vector.x(), 0.5 * rotation_vector.y(), 0.5 * rotation_vector.z())
        .normalized();
  }
  return Eigen::Quaterniond(Eigen::AngleAxisd(theta, rotation_vector / theta));
}

Eigen::Vector3d QuaternionLog(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0) q.coeffs() *= -1.0;  // shortest rotation, angle in [0, pi]
  const double sin_half = q.vec().norm();
  if (sin_half < 1e-10) return 2.0 * q.vec();
  const double theta = 2.0 * std::atan2(sin_half, q.w());
  return theta / sin_half * q.vec();
}

Rigid3d Interpolate(const Rigid3d& a, const Rigid3d& b, double alpha) {
  return Rigid3d(a.rotation.slerp(alpha, b.rotation), (1.0 - alpha) * a.translation + alpha * b.translation);
}

Rigid3d Stretched(const Rigid3d& a_from_b, double scale) {
  return Rigid3d(a_from_b.rotation, a_from_b.translation * scale);
}

}  // namespace semslam
