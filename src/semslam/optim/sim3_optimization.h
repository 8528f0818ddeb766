#pragma once
// Refinement of the similarity between two keyframes that close a loop (Mur-Artal et al. 2015, §VI-B):
// matched map points, each known in its own camera's frame, are reprojected across, point2 into image 1
// through camera1_from_camera2 and point1 into image 2 through its inverse. Huber kernel at the chi-square
// threshold, then matches failing the test are dropped and a second pass runs on the rest.

#include <vector>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/sim3.h"

namespace semslam {

struct Sim3Match {
  Eigen::Vector3d point1 = Eigen::Vector3d::Zero();  // the map point of keyframe 1, in camera 1's frame
  Eigen::Vector3d point2 = Eigen::Vector3d::Zero();  // its match of keyframe 2, in camera 2's frame
  Eigen::Vector2d pixel1 = Eigen::Vector2d::Zero();  // keypoint of point1 in image 1 (undistorted)
  Eigen::Vector2d pixel2 = Eigen::Vector2d::Zero();  // keypoint of point2 in image 2
  double inv_sigma2_1 = 1.0;  // inverse variances of the two keypoints' pyramid levels (> 0)
  double inv_sigma2_2 = 1.0;
};

struct Sim3RefinementProblem {
  PinholeCamera camera1;  // ideal pinholes
  PinholeCamera camera2;
  std::vector<Sim3Match> matches;
};

struct Sim3RefinementOptions {
  int iterations = 10;  // first pass, under the Huber kernel (ORB-SLAM: 5, from a RANSAC estimate)
  int refine_iterations =
      10;  // second pass without the dropped matches (`iterations` when none were dropped)

  void Check() const;  // throws InvalidArgument
};

struct Sim3RefinementResult {
  Sim3d camera1_from_camera2;
  // Per match, under the final transform: both reprojections within chi2_threshold, in front of both
  // cameras (a match dropped after the first pass counts again if it fits the final transform).
  std::vector<bool> inliers;
  int num_inliers = 0;
};

// chi2_threshold: on each whitened squared reprojection error (2 DoF; ORB-SLAM uses 10); the Huber threshold
// is its square root. fix_scale: SE(3) (stereo), the scale stays that of `initial_camera1_from_camera2`.
// Throws InvalidArgument on a bad problem (non-finite values, inv_sigma2 <= 0, distorted cameras).
Sim3RefinementResult OptimizeSim3(const Sim3RefinementProblem& problem,
                                  const Sim3d& initial_camera1_from_camera2, double chi2_threshold,
                                  bool fix_scale, const Sim3RefinementOptions& options = {});

}  // namespace semslam
