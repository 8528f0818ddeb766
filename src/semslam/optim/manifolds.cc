#include "semslam/optim/manifolds.h"

#include <algorithm>
#include <cmath>

#include "semslam/core/error.h"
#include "semslam/optim/internal.h"

namespace semslam::optim_internal {
namespace {

// [I; 0] (ambient x tangent, row-major).
void LiftedPlusJacobian(int ambient, int tangent, double* jacobian) {
  std::fill(jacobian, jacobian + ambient * tangent, 0.0);
  for (int i = 0; i < tangent; ++i) jacobian[i * tangent + i] = 1.0;
}

// [I 0] (tangent x ambient, row-major).
void LiftedMinusJacobian(int ambient, int tangent, double* jacobian) {
  std::fill(jacobian, jacobian + ambient * tangent, 0.0);
  for (int i = 0; i < tangent; ++i) jacobian[i * ambient + i] = 1.0;
}

void TakeLeadingColumns(int num_rows, int ambient, int tangent, const double* ambient_matrix,
                        double* tangent_matrix) {
  for (int r = 0; r < num_rows; ++r) {
    std::copy(ambient_matrix + r * ambient, ambient_matrix + r * ambient + tangent,
              tangent_matrix + r * tangent);
  }
}

}  // namespace

void RequirePinhole(const PinholeCamera& camera, const char* who) {
  Require(std::isfinite(camera.fx) && camera.fx > 0 && std::isfinite(camera.fy) && camera.fy > 0 &&
              std::isfinite(camera.cx) && std::isfinite(camera.cy),
          std::string(who) + ": camera intrinsics must be finite with fx, fy > 0");
  Require(camera.distortion.IsZero(),
          std::string(who) + ": the camera must be an ideal pinhole (undistort the keypoints first)");
}

void PackRigid(const Rigid3d& t, double* x) {
  const Eigen::Quaterniond q = t.rotation.normalized();
  x[0] = q.x();
  x[1] = q.y();
  x[2] = q.z();
  x[3] = q.w();
  x[4] = t.translation.x();
  x[5] = t.translation.y();
  x[6] = t.translation.z();
}

Rigid3d UnpackRigid(const double* x) {
  return Rigid3d(Eigen::Quaterniond(x[3], x[0], x[1], x[2]), Eigen::Vector3d(x[4], x[5], x[6]));
}

void PackSim3(const Sim3d& s, double* x) {
  const Eigen::Quaterniond q = s.rotation.normalized();
  x[0] = q.x();
  x[1] = q.y();
  x[2] = q.z();
  x[3] = q.w();
  x[4] = s.translation.x();
  x[5] = s.translation.y();
  x[6] = s.translation.z();
  x[7] = std::log(s.scale);
}

Sim3d UnpackSim3(const double* x) {
  return Sim3d(std::exp(x[7]), Eigen::Quaterniond(x[3], x[0], x[1], x[2]), Eigen::Vector3d(x[4], x[5], x[6]));
}

bool RigidLeftManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const Eigen::Map<const Eigen::Quaterniond> q(x);
  const Eigen::Map<const Eigen::Vector3d> t(x + 4);
  const Eigen::Map<const Eigen::Vector3d> rho(delta);
  const Eigen::Map<const Eigen::Vector3d> phi(delta + 3);
  const Eigen::Quaterniond dq = QuaternionExp(phi);
  Eigen::Map<Eigen::Quaterniond> q_out(x_plus_delta);
  Eigen::Map<Eigen::Vector3d> t_out(x_plus_delta + 4);
  const Eigen::Vector3d t_new = dq * t + rho;  // t may alias t_out
  q_out = (dq * q).normalized();
  t_out = t_new;
  return true;
}

bool RigidLeftManifold::PlusJacobian(const double*, double* jacobian) const {
  LiftedPlusJacobian(kRigidSize, 6, jacobian);
  return true;
}

bool RigidLeftManifold::RightMultiplyByPlusJacobian(const double*, int num_rows, const double* ambient_matrix,
                                                    double* tangent_matrix) const {
  TakeLeadingColumns(num_rows, kRigidSize, 6, ambient_matrix, tangent_matrix);
  return true;
}

bool RigidLeftManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  const Eigen::Map<const Eigen::Quaterniond> qx(x), qy(y);
  const Eigen::Map<const Eigen::Vector3d> tx(x + 4), ty(y + 4);
  const Eigen::Quaterniond dq = qy * qx.conjugate();
  const Eigen::Vector3d phi = QuaternionLog(dq);
  Eigen::Map<Eigen::Vector3d>{y_minus_x} = ty - QuaternionExp(phi) * tx;
  Eigen::Map<Eigen::Vector3d>(y_minus_x + 3) = phi;
  return true;
}

bool RigidLeftManifold::MinusJacobian(const double*, double* jacobian) const {
  LiftedMinusJacobian(kRigidSize, 6, jacobian);
  return true;
}

bool Sim3RightManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const Eigen::Map<const Eigen::Quaterniond> q(x);
  const Eigen::Map<const Eigen::Vector3d> t(x + 4);
  const double log_s = x[7];
  const Eigen::Map<const Eigen::Vector3d> rho(delta);
  const Eigen::Map<const Eigen::Vector3d> phi(delta + 3);
  const double sigma = fix_scale_ ? 0.0 : delta[6];
  const Eigen::Vector3d t_new = std::exp(log_s) * (q * rho) + t;
  const Eigen::Quaterniond q_new = (q * QuaternionExp(phi)).normalized();
  Eigen::Map<Eigen::Quaterniond>{x_plus_delta} = q_new;
  Eigen::Map<Eigen::Vector3d>(x_plus_delta + 4) = t_new;
  x_plus_delta[7] = log_s + sigma;
  return true;
}

bool Sim3RightManifold::PlusJacobian(const double*, double* jacobian) const {
  LiftedPlusJacobian(kSim3Size, TangentSize(), jacobian);
  return true;
}

bool Sim3RightManifold::RightMultiplyByPlusJacobian(const double*, int num_rows, const double* ambient_matrix,
                                                    double* tangent_matrix) const {
  TakeLeadingColumns(num_rows, kSim3Size, TangentSize(), ambient_matrix, tangent_matrix);
  return true;
}

bool Sim3RightManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  // x^-1 y = (e^sigma, Exp(phi), rho).
  const Eigen::Map<const Eigen::Quaterniond> qx(x), qy(y);
  const Eigen::Map<const Eigen::Vector3d> tx(x + 4), ty(y + 4);
  Eigen::Map<Eigen::Vector3d>{y_minus_x} = std::exp(-x[7]) * (qx.conjugate() * (ty - tx));
  Eigen::Map<Eigen::Vector3d>(y_minus_x + 3) = QuaternionLog(qx.conjugate() * qy);
  if (!fix_scale_) y_minus_x[6] = y[7] - x[7];
  return true;
}

bool Sim3RightManifold::MinusJacobian(const double*, double* jacobian) const {
  LiftedMinusJacobian(kSim3Size, TangentSize(), jacobian);
  return true;
}

}  // namespace semslam::optim_internal
