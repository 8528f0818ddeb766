#pragma once
// The similarity between two keyframes from their matched map points (loop closing): RANSAC over minimal sets
// of 3 point pairs with the closed-form absolute orientation (Horn 1987 / Umeyama 1991, alignment.h), with
// inliers decided by the reprojection error in both images; the scale is fixed to 1 (SE(3)) for metric maps.

#include <cstdint>
#include <optional>
#include <vector>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/sim3.h"

namespace semslam {

// Matched points of two keyframes, one entry per match in every vector.
struct Sim3Correspondences {
  PinholeCamera camera1;
  PinholeCamera camera2;
  Points3d points1;              // the match's map point in camera 1's frame
  Points3d points2;              // the matched map point in camera 2's frame
  Points2d pixels1;              // the keypoint in image 1 (raw pixels)
  Points2d pixels2;              // the keypoint in image 2
  std::vector<double> sigma2_1;  // variance of the keypoint position in image 1 (pixels^2, by pyramid level)
  std::vector<double> sigma2_2;
};

struct Sim3RansacOptions {
  bool fix_scale = false;  // SE(3) (stereo, RGB-D: metric maps), scale = 1
  int min_inliers = 20;    // fewer: no solution
  int max_iterations = 300;
  double confidence = 0.99;  // adaptive iteration count: P(one all-inlier sample)
  double chi2_threshold =
      9.210;  // (reprojection error)^2 / sigma^2 below this in both images: chi-square 99 %, 2 dof
  // After RANSAC, up to 3 rounds of refinement on the inliers and reclassification: the scale from their 3D
  // alignment weighted by 1 / depth^2, rotation and translation by this many Levenberg-Marquardt iterations
  // on the reprojection error in both images. 0: the best minimal-sample estimate as is.
  int refine_iterations = 10;
  std::uint64_t seed = 1;

  // Throws InvalidArgument naming the bad field.
  void Check() const;
};

struct Sim3RansacResult {
  Sim3d camera1_from_camera2;  // points1 ~ camera1_from_camera2 * points2
  std::vector<bool> inliers;   // one per match
  int num_inliers = 0;
  int iterations = 0;  // RANSAC samples drawn
};

// nullopt with fewer than max(3, min_inliers) matches, when every sample is degenerate, or with fewer than
// min_inliers inliers. Throws InvalidArgument for bad options or cameras, mismatched sizes, non-finite values
// or non-positive variances.
std::optional<Sim3RansacResult> EstimateSim3Ransac(const Sim3Correspondences& correspondences,
                                                   const Sim3RansacOptions& options);

// Inlier flags (and their count) of a given transform: chi2 below `chi2_threshold` in both images.
int ClassifySim3Inliers(const Sim3d& camera1_from_camera2, const Sim3Correspondences& correspondences,
                        double chi2_threshold, std::vector<bool>* inliers);

// The scale a transform leaves between two views' own 3D points: the median over the matches of
// |point1| / |camera1_from_camera2 * point2|, distances from camera 1 (about 1 when it aligns the two
// structures). Reprojection alone does not hold it where the two cameras stand close together: a similarity
// whose scale and translation shrink together moves no projection, and a refinement on reprojection can drift
// to a scale near 0. Throws InvalidArgument for no matches, mismatched sizes or non-finite points.
double MedianDepthRatio(const Sim3d& camera1_from_camera2, const Points3d& points1, const Points3d& points2);

// Whether such a ratio lies within `factor` (> 1) of 1, either way.
inline bool DepthRatioWithin(double ratio, double factor) { return ratio <= factor && ratio * factor >= 1.0; }

}  // namespace semslam
