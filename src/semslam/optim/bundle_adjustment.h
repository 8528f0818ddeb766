#pragma once
// Bundle adjustment of keyframe poses and map points (Triggs et al. 2000) with the outlier handling of
// ORB-SLAM's local and global BA (Mur-Artal et al. 2015, 2017): Huber kernels at the chi-square thresholds,
// and optionally a second pass without the kernel after the outliers of the first are dropped. Poses are
// camera_from_world; the gauge is fixed by the fixed poses (one for stereo, two for monocular maps).

#include <atomic>
#include <optional>
#include <vector>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/rigid3.h"
#include "semslam/optim/chi_square.h"

namespace semslam {

struct BundleAdjustmentObservation {
  int pose = -1;                                    // index into BundleAdjustmentProblem::camera_from_world
  int point = -1;                                   // index into BundleAdjustmentProblem::points
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // undistorted keypoint
  double right_u = -1.0;                            // stereo: u in the right image; < 0: monocular
  double inv_sigma2 = 1.0;                          // 1 / sigma^2 of the keypoint's pyramid level (> 0)
};

// A soft prior on the relative pose of two of the problem's poses: it holds parts of a map that share no
// points where they are relative to each other (the two sides of a gap in tracking, map/map.h's GapLink),
// which the observations alone leave free. Residual: [translation (in the problem's units); rotation vector]
// of a_from_b^-1 * camera_from_world[a] * camera_from_world[b]^-1, each part over its sigma.
struct BundleAdjustmentPosePrior {
  int a = -1;  // indices into BundleAdjustmentProblem::camera_from_world
  int b = -1;
  Rigid3d a_from_b;
  double sigma_translation = 1.0;
  double sigma_rotation = 1.0;  // rad
};

// In and out: BundleAdjust() writes the optimized poses and points back into the problem.
struct BundleAdjustmentProblem {
  PinholeCamera camera;   // ideal pinhole shared by all keyframes
  double baseline = 0.0;  // stereo baseline in metres (> 0 when any observation has right_u >= 0)
  std::vector<Rigid3d> camera_from_world;
  std::vector<bool> pose_fixed;         // one per pose
  std::vector<Eigen::Vector3d> points;  // world frame
  std::vector<BundleAdjustmentObservation> observations;
  std::vector<BundleAdjustmentPosePrior> pose_priors;
};

enum class BundleAdjustmentSolver {
  kAuto,  // dense Schur complement up to 60 free poses, sparse above
  kDenseSchur,
  kSparseSchur,
  kIterativeSchur,
};

struct BundleAdjustmentOptions {
  int iterations = 10;  // Levenberg-Marquardt iterations of the (first) pass
  // ORB-SLAM's local BA: after the first pass, observations failing the chi-square test (or behind their
  // camera) are dropped and a second pass of `refine_iterations` runs on the rest without the kernel.
  bool refine_without_outliers = false;
  int refine_iterations = 10;
  double chi2_mono = kChi2Mono;      // Huber threshold delta^2 and outlier test, monocular observations
  double chi2_stereo = kChi2Stereo;  // the same for stereo ones
  // Set (from another thread) to stop: the solver returns after the current iteration, keeping its progress.
  std::atomic<bool>* abort = nullptr;
  BundleAdjustmentSolver solver = BundleAdjustmentSolver::kAuto;
  int num_threads = 1;
  // Self-calibration, monocular problems only: the focal length (fx / fy kept), the principal point and two
  // radial terms (k1, k2, applied to the undistorted keypoints) are refined too, under weak priors at the
  // problem's camera. A published calibration a percent off bends monocular scale in slow turns; the camera
  // found is returned in BundleAdjustmentResult::refined_camera, the problem's own camera is left alone.
  bool refine_intrinsics = false;

  void Check() const;  // throws InvalidArgument
};

struct BundleAdjustmentResult {
  // Per observation: failed the chi-square test or lies behind its camera after the optimization (with
  // refine_without_outliers, also those dropped after the first pass).
  std::vector<bool> outlier;
  int num_outliers = 0;
  int iterations = 0;        // over both passes
  double initial_rms = 0.0;  // RMS whitened reprojection error over the inliers before ...
  double final_rms = 0.0;    // ... and after the optimization
  // The robust cost over every observation, each whitened squared error capped at its chi-square threshold
  // (behind the camera: the threshold), before and after: comparable between runs on the same observations.
  double initial_capped_chi2 = 0.0;
  double final_capped_chi2 = 0.0;
  bool aborted = false;
  // With refine_intrinsics: the camera the poses and points were optimized with.
  std::optional<PinholeCamera> refined_camera;
};

// Optimizes the free poses and every observed point in place. Throws InvalidArgument on a bad problem
// (sizes, indices, non-finite values, inv_sigma2 <= 0, a stereo observation without a baseline, a distorted
// camera, a pose prior between one pose or with a sigma <= 0). Points observed by no observation are left
// alone.
BundleAdjustmentResult BundleAdjust(BundleAdjustmentProblem& problem,
                                    const BundleAdjustmentOptions& options = {});

// Whitened squared reprojection error (chi-square statistic) of one observation; +infinity behind the camera.
double ReprojectionChi2(const BundleAdjustmentProblem& problem,
                        const BundleAdjustmentObservation& observation);

}  // namespace semslam
