#pragma once
// Camera pose from 2D-3D correspondences: the minimal P3P solver (Grunert 1841, in the formulation reviewed
// by Haralick et al. 1994: law of cosines, a quartic in the ratio of two distances), RANSAC around it with an
// adaptive iteration count, and a Levenberg-Marquardt refinement of the reprojection error on the inliers.
// Observations are bearings (unit rays in the camera frame, PinholeCamera::Unproject), so the solver knows no
// intrinsics; pixel thresholds are converted with a focal length.

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "semslam/geometry/rigid3.h"

namespace semslam {

// Up to 4 poses camera_from_world with camera_from_world * world_points[i] along bearings[i]. Empty for a
// degenerate triple (coincident or collinear points, parallel bearings).
std::vector<Rigid3d> SolveP3P(const std::array<Eigen::Vector3d, 3>& world_points,
                              const std::array<Eigen::Vector3d, 3>& bearings);

// Squared reprojection error on the normalized image plane (z = 1) of a world point seen along `bearing`;
// infinite when the point or the bearing is not in front of the camera.
double SquaredNormalizedError(const Rigid3d& camera_from_world, const Eigen::Vector3d& world_point,
                              const Eigen::Vector3d& bearing);

// Levenberg-Marquardt on sum_i |normalized error_i|^2 over the correspondences with use[i] (all when `use` is
// empty), starting from `camera_from_world`. Returns the refined pose (the start when fewer than 3 are used).
Rigid3d RefinePose(const Rigid3d& camera_from_world, const Points3d& world_points, const Points3d& bearings,
                   const std::vector<bool>& use = {}, int max_iterations = 10);

struct PnpRansacOptions {
  // Inlier threshold on the reprojection error, in pixels of a camera with focal length `focal_length` (which
  // has no default: the caller's camera, e.g. PinholeCamera::fx).
  double max_reprojection_error_px = 2.0 * 2.447;  // 2 sigma * sqrt(chi2 95 %, 2 dof)
  double focal_length = 0.0;
  double confidence = 0.99;  // adaptive iteration count: P(one all-inlier sample)
  int max_iterations = 300;
  int min_inliers = 10;        // fewer (after refinement): no solution
  int refine_iterations = 10;  // Levenberg-Marquardt iterations per refinement (0: none)
  std::uint64_t seed = 1;

  // Throws InvalidArgument naming the bad field.
  void Check() const;
};

struct PnpResult {
  Rigid3d camera_from_world;
  std::vector<bool> inliers;  // one per correspondence
  int num_inliers = 0;
  double rms_error_px = 0.0;  // over the inliers, in pixels of focal_length
  int iterations = 0;         // RANSAC samples drawn
};

// `world_points[i]` is seen along `bearings[i]` (any length, z > 0; those with z <= 0 are never inliers).
// nullopt with fewer than max(4, min_inliers) correspondences, a degenerate configuration, or fewer than
// min_inliers inliers. Throws InvalidArgument for bad options, mismatched sizes or non-finite input.
std::optional<PnpResult> SolvePnpRansac(const Points3d& world_points, const Points3d& bearings,
                                        const PnpRansacOptions& options);

}  // namespace semslam
