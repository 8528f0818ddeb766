#pragma once
// Internal to optim: factories for the analytic cost functions of the optimizers, so that tests can check
// their Jacobians against numeric differentiation (ceres::GradientChecker with the manifolds of
// manifolds.h). The caller owns the returned object.

#include <ceres/cost_function.h>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/sim3.h"

namespace semslam::optim_internal {

// Bundle adjustment: parameters camera_from_world (RigidLeftManifold) and a world point; stereo when
// right_u >= 0 (bf = fx * baseline).
ceres::CostFunction* NewReprojectionCost(const PinholeCamera& camera, double bf, const Eigen::Vector2d& pixel,
                                         double right_u, double sqrt_info);

// Self-calibrating monocular bundle adjustment: parameters camera_from_world (RigidLeftManifold), a world
// point and the intrinsics [f, cx, cy, k1, k2] (fy = f * aspect, radial distortion as
// PinholeCamera::Project).
ceres::CostFunction* NewSelfCalibratingReprojectionCost(const Eigen::Vector2d& pixel, double aspect,
                                                        double sqrt_info);

// Bundle adjustment's pose prior (BundleAdjustmentPosePrior): parameters camera_from_world of a and b
// (RigidLeftManifold).
ceres::CostFunction* NewPosePriorCost(const Rigid3d& a_from_b, double sigma_translation,
                                      double sigma_rotation);

// Pose graph: parameters world_from_a, world_from_b (Sim3RightManifold); the residual is multiplied by
// sqrt_information.
ceres::CostFunction* NewRelativeSim3Cost(const Sim3d& a_from_b,
                                         const Eigen::Matrix<double, 7, 7>& sqrt_information);
// Pose graph: parameter world_from_node, and prior_from_graph when `framed`.
ceres::CostFunction* NewPositionPriorCost(const Eigen::Vector3d& target, double sigma, bool framed,
                                          const Eigen::Vector3d& offset = Eigen::Vector3d::Zero());
// (R * axis - target) / sigma of a Sim(3) node: the direction of the node's axis
// (PoseGraph::AddDirectionPrior).
ceres::CostFunction* NewDirectionPriorCost(const Eigen::Vector3d& axis, const Eigen::Vector3d& target,
                                           double sigma);

// Sim(3) refinement: parameter camera1_from_camera2 (Sim3RightManifold). into_camera1: `point` is in camera
// 2's frame and `pixel` in image 1; otherwise `point` is in camera 1's frame and `pixel` in image 2.
ceres::CostFunction* NewSim3ReprojectionCost(const PinholeCamera& camera, const Eigen::Vector3d& point,
                                             const Eigen::Vector2d& pixel, double sqrt_info,
                                             bool into_camera1);

}  // namespace semslam::optim_internal
