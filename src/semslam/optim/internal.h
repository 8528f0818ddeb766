#pragma once
// Internal to optim (no Ceres here): small Lie-group and projection helpers shared by the optimizers.

#include <cmath>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/rigid3.h"

namespace semslam::optim_internal {

// Inverse of the left Jacobian of SO(3): Exp(d) Exp(theta) = Exp(theta + Jl^-1(theta) d) to first order.
inline Eigen::Matrix3d SO3LeftJacobianInverse(const Eigen::Vector3d& theta) {
  const double angle = theta.norm();
  const Eigen::Matrix3d w = SkewSymmetric(theta);
  double coeff = 1.0 / 12.0;
  if (angle > 1e-6) {
    const double half = 0.5 * angle;
    coeff = (1.0 - half * std::cos(half) / std::sin(half)) / (angle * angle);
  }
  return Eigen::Matrix3d::Identity() - 0.5 * w + coeff * w * w;
}

// Inverse of the right Jacobian: Exp(theta) Exp(d) = Exp(theta + Jr^-1(theta) d); Jr^-1(theta) =
// Jl^-1(-theta).
inline Eigen::Matrix3d SO3RightJacobianInverse(const Eigen::Vector3d& theta) {
  return SO3LeftJacobianInverse(-theta);
}

// Whether a camera-frame point projects: finite, and in front of the camera by more than a rounding error.
// The cost functions and the checks that choose which observations they get must agree on it, or one point at
// the very centre of a camera stops a whole solve at its first evaluation (Ceres: "Residual and Jacobian
// evaluation failed"). A trial step that overflows (a Sim(3) step to scale exp(9000)) is refused here rather
// than handed to Ceres as NaN residuals, which it rejects the same way but logs page by page.
inline bool InFrontOfCamera(const Eigen::Vector3d& p) { return p.allFinite() && p.z() > 1e-9; }

// The optimizers model an ideal pinhole (keypoints are undistorted before they get here).
void RequirePinhole(const PinholeCamera& camera, const char* who);

// Huber cost of a squared, whitened error `e2` with threshold delta^2 = `delta2`, and its IRLS weight.
inline double HuberCost(double e2, double delta2) {
  return e2 <= delta2 ? e2 : 2.0 * std::sqrt(e2 * delta2) - delta2;
}
inline double HuberWeight(double e2, double delta2) { return e2 <= delta2 ? 1.0 : std::sqrt(delta2 / e2); }

}  // namespace semslam::optim_internal
