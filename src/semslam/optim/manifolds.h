#pragma once
// Internal to optim (the only header that includes Ceres; included by optim's .cc files only): manifolds for
// SE(3) poses and Sim(3) transforms whose cost functions supply analytic Jacobians in the tangent space.
//
// The "lifted Jacobian" convention: a cost function writes its Jacobian with respect to the tangent
// perturbation into the first TangentSize() columns of the ambient Jacobian and zeros into the rest, and
// PlusJacobian() is [I; 0]. Ceres' product (ambient Jacobian) * PlusJacobian then is exactly the tangent
// Jacobian, without Ceres multiplying by a 7x6 quaternion Jacobian per residual. Plus() and Minus() are the
// true group operations, so the optimization itself is exact; only PlusJacobian() is not the derivative of
// Plus() in ambient coordinates, which Ceres uses solely in that product.

#include <ceres/manifold.h>

#include "semslam/geometry/rigid3.h"
#include "semslam/geometry/sim3.h"

namespace semslam::optim_internal {

// Rigid transform as [qx qy qz qw tx ty tz] (Eigen's quaternion coefficient order, then translation).
inline constexpr int kRigidSize = 7;
void PackRigid(const Rigid3d& t, double* x);
Rigid3d UnpackRigid(const double* x);

// Similarity as [qx qy qz qw tx ty tz log(scale)].
inline constexpr int kSim3Size = 8;
void PackSim3(const Sim3d& s, double* x);
Sim3d UnpackSim3(const double* x);

// SE(3) with a left perturbation, for camera_from_world: tangent [rho, phi],
// Plus(T, [rho, phi]) = [Exp(phi) | rho] * T, so a camera-frame point p = T * X moves to Exp(phi) p + rho
// and dp / d[rho, phi] = [I, -[p]x].
class RigidLeftManifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return kRigidSize; }
  int TangentSize() const override { return 6; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool RightMultiplyByPlusJacobian(const double* x, int num_rows, const double* ambient_matrix,
                                   double* tangent_matrix) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

// Sim(3) with a right perturbation, for world_from_node and camera1_from_camera2: tangent
// [rho, phi, sigma] (or [rho, phi] with the scale fixed), Plus(S, d) = S * (e^sigma, Exp(phi), rho), so
// S * X moves to S * (e^sigma Exp(phi) X + rho).
class Sim3RightManifold final : public ceres::Manifold {
 public:
  explicit Sim3RightManifold(bool fix_scale) : fix_scale_(fix_scale) {}
  int AmbientSize() const override { return kSim3Size; }
  int TangentSize() const override { return fix_scale_ ? 6 : 7; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool RightMultiplyByPlusJacobian(const double* x, int num_rows, const double* ambient_matrix,
                                   double* tangent_matrix) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;

 private:
  bool fix_scale_;
};

}  // namespace semslam::optim_internal
