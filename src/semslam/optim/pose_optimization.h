#pragma once
// Motion-only bundle adjustment: the pose of one camera from matches of its keypoints to known world points
// (Mur-Artal et al. 2015, 2017). Rounds of Levenberg-Marquardt under a Huber kernel; after each round
// every observation is classified by a chi-square test at the level's inverse variance, outliers sit out
// the next round (and come back if they fit again), and the last round runs without the kernel.

#include <vector>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/rigid3.h"
#include "semslam/optim/chi_square.h"

namespace semslam {

struct PoseObservation {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // world frame
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // undistorted keypoint
  double right_u = -1.0;                            // stereo: u in the right image; < 0: monocular
  double inv_sigma2 = 1.0;                          // 1 / sigma^2 of the keypoint's pyramid level (> 0)
};

struct PoseOptimizationProblem {
  PinholeCamera camera;       // ideal pinhole (no distortion)
  Rigid3d camera_from_world;  // initial guess
  std::vector<PoseObservation> observations;
  double baseline = 0.0;  // stereo baseline in metres (> 0 when any observation has right_u >= 0)
};

enum class PoseSolver {
  kGaussNewton,  // hand-written 6-DoF Levenberg-Marquardt (the default: ~5x faster than Ceres per call)
  kCeres,        // the same optimization through Ceres (reference; slower per call)
};

struct PoseOptimizationOptions {
  int rounds = 4;
  int iterations_per_round = 10;
  int robust_rounds = 3;             // the first `robust_rounds` rounds use the Huber kernel, the others none
  double chi2_mono = kChi2Mono;      // Huber threshold and outlier test (whitened squared error), mono
  double chi2_stereo = kChi2Stereo;  // the same for stereo
  int min_inliers = 10;              // no further rounds once fewer inliers remain
  PoseSolver solver = PoseSolver::kGaussNewton;

  void Check() const;  // throws InvalidArgument
};

struct PoseOptimizationResult {
  Rigid3d camera_from_world;
  std::vector<bool> inliers;  // per observation: passed the chi-square test after the last round
  int num_inliers = 0;
};

// Throws InvalidArgument on a bad problem (non-finite values, inv_sigma2 <= 0, a stereo observation without
// a baseline, a distorted camera). With no observations the initial pose is returned.
PoseOptimizationResult OptimizePose(const PoseOptimizationProblem& problem,
                                    const PoseOptimizationOptions& options = {});

}  // namespace semslam
