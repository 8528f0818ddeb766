#include "semslam/geometry/epipolar.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>
#include <limits>

namespace semslam {
namespace {

using Matrix9d = Eigen::Matrix<double, 9, 9>;
using Vector9d = Eigen::Matrix<double, 9, 1>;

// The unit vector minimizing |A f| given A^T A; nullopt when the minimum is not unique (a null space of
// dimension > 1: too few independent constraints).
std::optional<Vector9d> NullVector(const Matrix9d& ata) {
  const Eigen::SelfAdjointEigenSolver<Matrix9d> eigen(ata);
  if (eigen.info() != Eigen::Success) return std::nullopt;
  const Vector9d values = eigen.eigenvalues();  // ascending
  if (!(values(8) > 0) || values(1) <= 1e-12 * values(8)) return std::nullopt;
  return Vector9d(eigen.eigenvectors().col(0));
}

Eigen::Matrix3d FromRowMajor(const Vector9d& f) {
  Eigen::Matrix3d m;
  m << f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7), f(8);
  return m;
}

bool AllFinite(const Points2d& points) {
  for (const auto& p : points) {
    if (!p.allFinite()) return false;
  }
  return true;
}

}  // namespace

Eigen::Matrix3d HartleyNormalization(const Points2d& points) {
  Eigen::Matrix3d t = Eigen::Matrix3d::Identity();
  if (points.empty()) return t;
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const auto& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  double mean_distance = 0.0;
  for (const auto& p : points) mean_distance += (p - centroid).norm();
  mean_distance /= static_cast<double>(points.size());
  if (!(mean_distance > 0) || !std::isfinite(mean_distance)) return t;
  const double s = std::sqrt(2.0) / mean_distance;
  t << s, 0, -s * centroid.x(), 0, s, -s * centroid.y(), 0, 0, 1;
  return t;
}

std::optional<Eigen::Matrix3d> EstimateHomography(const Points2d& x1, const Points2d& x2) {
  if (x1.size() < 4 || x1.size() != x2.size() || !AllFinite(x1) || !AllFinite(x2)) return std::nullopt;
  const Eigen::Matrix3d t1 = HartleyNormalization(x1);
  const Eigen::Matrix3d t2 = HartleyNormalization(x2);
  Matrix9d ata = Matrix9d::Zero();
  for (size_t i = 0; i < x1.size(); ++i) {
    const Eigen::Vector3d p = t1 * x1[i].homogeneous();
    const Eigen::Vector3d q = t2 * x2[i].homogeneous();
    // Two rows of q x (H p) = 0.
    Vector9d r1, r2;
    r1 << 0, 0, 0, -p.x(), -p.y(), -1, q.y() * p.x(), q.y() * p.y(), q.y();
    r2 << p.x(), p.y(), 1, 0, 0, 0, -q.x() * p.x(), -q.x() * p.y(), -q.x();
    ata.selfadjointView<Eigen::Lower>().rankUpdate(r1);
    ata.selfadjointView<Eigen::Lower>().rankUpdate(r2);
  }
  ata = ata.selfadjointView<Eigen::Lower>();
  const auto h = NullVector(ata);
  if (!h) return std::nullopt;
  Eigen::Matrix3d homography = t2.inverse() * FromRowMajor(*h) * t1;
  const double norm = homography.norm();
  if (!(norm > 0) || !homography.allFinite()) return std::nullopt;
  homography /= norm;
  // A rank-deficient H maps the plane onto a line: three of the points were collinear.
  const Eigen::Vector3d singular = homography.jacobiSvd().singularValues();
  if (singular(2) <= 1e-9 * singular(0)) return std::nullopt;
  return homography;
}

std::optional<Eigen::Matrix3d> EstimateFundamental(const Points2d& x1, const Points2d& x2) {
  if (x1.size() < 8 || x1.size() != x2.size() || !AllFinite(x1) || !AllFinite(x2)) return std::nullopt;
  const Eigen::Matrix3d t1 = HartleyNormalization(x1);
  const Eigen::Matrix3d t2 = HartleyNormalization(x2);
  Matrix9d ata = Matrix9d::Zero();
  for (size_t i = 0; i < x1.size(); ++i) {
    const Eigen::Vector3d p = t1 * x1[i].homogeneous();
    const Eigen::Vector3d q = t2 * x2[i].homogeneous();
    // q^T F p = 0, F row-major.
    Vector9d r;
    r << q.x() * p.x(), q.x() * p.y(), q.x(), q.y() * p.x(), q.y() * p.y(), q.y(), p.x(), p.y(), 1;
    ata.selfadjointView<Eigen::Lower>().rankUpdate(r);
  }
  ata = ata.selfadjointView<Eigen::Lower>();
  const auto f = NullVector(ata);
  if (!f) return std::nullopt;
  // Closest rank-2 matrix (Frobenius norm), then back to the input coordinates.
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(FromRowMajor(*f), Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d singular = svd.singularValues();
  singular(2) = 0.0;
  Eigen::Matrix3d fundamental =
      t2.transpose() * svd.matrixU() * singular.asDiagonal() * svd.matrixV().transpose() * t1;
  const double norm = fundamental.norm();
  if (!(norm > 0) || !fundamental.allFinite()) return std::nullopt;
  return fundamental / norm;
}

std::vector<HomographyMotion> DecomposeHomography(const Eigen::Matrix3d& h) {
  std::vector<HomographyMotion> motions;
  if (!h.allFinite()) return motions;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d& u = svd.matrixU();
  const Eigen::Matrix3d& v = svd.matrixV();
  const double d1 = svd.singularValues()(0);
  const double d2 = svd.singularValues()(1);
  const double d3 = svd.singularValues()(2);
  if (!(d3 > 0)) return motions;  // rank deficient: not a homography
  const double s = u.determinant() * v.determinant();

  // Faugeras & Lustman: with A = U diag(d1, d2, d3) V^T = d R + t n^T, R' = s U^T R V, t' = U^T t, n' = V^T n
  // and d' = s d satisfy diag(d1, d2, d3) = d' R' + t' n'^T, which forces d' = +-d2 and n' = (x1, 0, x3).
  if (d1 - d3 <= 1e-10 * d1) {
    HomographyMotion rotation_only;
    rotation_only.camera2_from_camera1 =
        Rigid3d(Eigen::Matrix3d(s * u * v.transpose()), Eigen::Vector3d::Zero());
    motions.push_back(rotation_only);
    return motions;
  }
  const double denominator = d1 * d1 - d3 * d3;
  const double x1_abs = std::sqrt(std::max(0.0, (d1 * d1 - d2 * d2) / denominator));
  const double x3_abs = std::sqrt(std::max(0.0, (d2 * d2 - d3 * d3) / denominator));
  for (const double d_prime_sign : {1.0, -1.0}) {
    for (const double e1 : {1.0, -1.0}) {
      for (const double e3 : {1.0, -1.0}) {
        const double x1 = e1 * x1_abs;
        const double x3 = e3 * x3_abs;
        Eigen::Matrix3d r_prime;
        Eigen::Vector3d t_prime;
        if (d_prime_sign > 0) {
          // R' is a rotation about e2.
          const double sin_theta = (d1 - d3) * x1 * x3 / d2;
          const double cos_theta = (d1 * x3 * x3 + d3 * x1 * x1) / d2;
          r_prime << cos_theta, 0, -sin_theta, 0, 1, 0, sin_theta, 0, cos_theta;
          t_prime = (d1 - d3) * Eigen::Vector3d(x1, 0, -x3);
        } else {
          // R' is a half-turn about the axis (cos(phi/2), 0, sin(phi/2)).
          const double sin_phi = (d1 + d3) * x1 * x3 / d2;
          const double cos_phi = (d3 * x1 * x1 - d1 * x3 * x3) / d2;
          r_prime << cos_phi, 0, sin_phi, 0, -1, 0, sin_phi, 0, -cos_phi;
          t_prime = (d1 + d3) * Eigen::Vector3d(x1, 0, x3);
        }
        const double d = s * d_prime_sign * d2;
        const Eigen::Matrix3d r = s * u * r_prime * v.transpose();
        HomographyMotion motion;
        motion.camera2_from_camera1 = Rigid3d(r, Eigen::Vector3d(u * t_prime / d));
        motion.normal = v * Eigen::Vector3d(x1, 0, x3);
        motions.push_back(motion);
      }
    }
  }
  return motions;
}

std::vector<Rigid3d> DecomposeEssential(const Eigen::Matrix3d& e) {
  std::vector<Rigid3d> motions;
  if (!e.allFinite()) return motions;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(e, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  Eigen::Matrix3d v = svd.matrixV();
  if (!(svd.singularValues()(1) > 0)) return motions;
  // The third singular value is (ideally) zero, so the last columns may be flipped to make U and V rotations.
  if (u.determinant() < 0) u.col(2) *= -1.0;
  if (v.determinant() < 0) v.col(2) *= -1.0;
  Eigen::Matrix3d w;
  w << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const Eigen::Matrix3d r1 = u * w * v.transpose();
  const Eigen::Matrix3d r2 = u * w.transpose() * v.transpose();
  const Eigen::Vector3d t = u.col(2);
  motions.emplace_back(r1, t);
  motions.emplace_back(r1, Eigen::Vector3d(-t));
  motions.emplace_back(r2, t);
  motions.emplace_back(r2, Eigen::Vector3d(-t));
  return motions;
}

double SampsonError(const Eigen::Matrix3d& f, const Eigen::Vector2d& x1, const Eigen::Vector2d& x2) {
  const Eigen::Vector3d p1 = x1.homogeneous();
  const Eigen::Vector3d p2 = x2.homogeneous();
  const Eigen::Vector3d line2 = f * p1;
  const Eigen::Vector3d line1 = f.transpose() * p2;
  const double denominator = line2.head<2>().squaredNorm() + line1.head<2>().squaredNorm();
  if (!(denominator > 0)) return std::numeric_limits<double>::infinity();
  return p2.dot(line2) / std::sqrt(denominator);
}

Rigid3d RefineRelativePose(const Rigid3d& camera2_from_camera1, const Points2d& x1, const Points2d& x2,
                           const std::vector<bool>& use, int max_iterations) {
  if (x1.size() != x2.size() || (!use.empty() && use.size() != x1.size())) return camera2_from_camera1;
  std::vector<size_t> used;
  for (size_t i = 0; i < x1.size(); ++i) {
    if (use.empty() || use[i]) used.push_back(i);
  }
  const double t_norm = camera2_from_camera1.translation.norm();
  if (used.size() < 5 || !(t_norm > 0)) return camera2_from_camera1;

  using Vector5d = Eigen::Matrix<double, 5, 1>;
  using Matrix5d = Eigen::Matrix<double, 5, 5>;
  // State: R and unit t; a step (w, a, b) moves R to Exp(w) R and t to normalize(t + a e1 + b e2), with e1,
  // e2 an orthonormal basis of the plane orthogonal to t.
  struct State {
    Eigen::Matrix3d r;
    Eigen::Vector3d t;
  };
  const auto apply = [](const State& s, const Vector5d& step) {
    const Eigen::Vector3d e1 = s.t.unitOrthogonal();
    const Eigen::Vector3d e2 = s.t.cross(e1);
    State next;
    next.r = QuaternionExp(step.head<3>()).toRotationMatrix() * s.r;
    next.t = (s.t + step(3) * e1 + step(4) * e2).normalized();
    return next;
  };
  const auto residuals = [&](const State& s) {
    const Eigen::Matrix3d e = SkewSymmetric(s.t) * s.r;
    Eigen::VectorXd r(static_cast<Eigen::Index>(used.size()));
    for (size_t k = 0; k < used.size(); ++k)
      r(static_cast<Eigen::Index>(k)) = SampsonError(e, x1[used[k]], x2[used[k]]);
    return r;
  };

  State state{camera2_from_camera1.rotation.toRotationMatrix(), camera2_from_camera1.translation / t_norm};
  Eigen::VectorXd r = residuals(state);
  if (!r.allFinite()) return camera2_from_camera1;
  double cost = r.squaredNorm();
  double lambda = 1e-4;
  constexpr double kStep = 1e-7;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    Eigen::MatrixXd jacobian(r.size(), 5);
    for (int j = 0; j < 5; ++j) {
      Vector5d delta = Vector5d::Zero();
      delta(j) = kStep;
      jacobian.col(j) = (residuals(apply(state, delta)) - r) / kStep;
    }
    const Matrix5d jtj = jacobian.transpose() * jacobian;
    const Vector5d jtr = jacobian.transpose() * r;
    bool improved = false;
    while (lambda < 1e8) {
      Matrix5d damped = jtj;
      damped.diagonal() += lambda * jtj.diagonal().cwiseMax(1e-12);
      const Vector5d step = damped.ldlt().solve(-jtr);
      if (!step.allFinite()) break;
      const State candidate = apply(state, step);
      const Eigen::VectorXd candidate_r = residuals(candidate);
      const double candidate_cost = candidate_r.squaredNorm();
      if (candidate_cost < cost) {
        const bool converged = cost - candidate_cost <= 1e-10 * cost;
        state = candidate;
        r = candidate_r;
        cost = candidate_cost;
        lambda = std::max(lambda * 0.1, 1e-10);
        improved = !converged;
        break;
      }
      lambda *= 10.0;
    }
    if (!improved) break;
  }
  return Rigid3d(state.r, state.t * t_norm);
}

}  // namespace semslam
