#pragma once
// Monocular map initialization from two views (Mur-Artal et al. 2015, ORB-SLAM §IV): a homography and a
// fundamental matrix are estimated in parallel, by RANSAC over the same random 8-point sets (H by DLT on the
// first 4 matches of a set, F by the eight-point algorithm on all 8; both refit on their inliers), and scored
// by their symmetric transfer errors; the homography is chosen for planar or low-parallax scenes (S_H / (S_H
// + S_F) > homography_ratio), the fundamental matrix otherwise. The chosen model is decomposed into its
// motion hypotheses (8 for H; 4 for E = K^T F K, after refining its motion on the Sampson error, as the
// linear estimate is biased at small baselines), the inliers are triangulated under each, and the
// best is accepted only when it is unambiguous, explains most inliers and has enough parallax.

#include <cstdint>
#include <string>
#include <vector>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/rigid3.h"

namespace semslam {

struct TwoViewOptions {
  std::uint64_t seed = 1;    // the RANSAC sample sets are a function of the seed only
  int max_iterations = 200;  // sample sets of 8 matches, shared by H and F
  double sigma_px = 1.0;     // standard deviation of a keypoint position
  // Inlier thresholds on (error / sigma)^2: chi-square 95 % for 2 dof (H transfer error, per image) and 1 dof
  // (F: distance to the epipolar line). Each image's error below its threshold adds score_threshold - chi2.
  double chi2_homography = 5.991;
  double chi2_fundamental = 3.841;
  double score_threshold = 5.991;
  double homography_ratio = 0.45;  // choose H when S_H / (S_H + S_F) is above this
  bool parallel = true;            // H and F on two threads
  // Levenberg-Marquardt iterations refining the motion of a fundamental matrix on the Sampson error of its
  // inliers before the decomposition (0: the linear eight-point estimate as is).
  int refine_iterations = 10;

  // Reconstruction. A triangulated inlier is "good" when it reprojects within reprojection_sigmas * sigma in
  // both images and lies in front of both cameras; it is returned as a map point when its parallax is also at
  // least min_point_parallax_deg (the depth of a point with less is not trusted).
  double reprojection_sigmas = 2.0;
  double min_point_parallax_deg = 0.4;
  // Acceptance: the parallax of the `parallax_rank`-th most parallax-rich good point (the least one when there
  // are fewer) >= min_parallax_deg: a forward-moving camera sees most points near the focus of expansion with
  // little parallax, so a median would wait far too long; enough well-triangulated points is what matters. At least
  // min_good_points good points and min_good_ratio of the model's inliers; the second best hypothesis with
  // fewer than ambiguity_ratio times the best's good points.
  double min_parallax_deg = 1.0;
  int parallax_rank = 50;
  // The ranking counts at most parallax_cell_share * parallax_rank points (rounded up) from any one cell of a
  // parallax_grid_cols x parallax_grid_rows grid over image 1: one object close to the camera cannot pass the
  // test alone, least of all one that moves on its own (a vehicle's features can fit the epipolar geometry
  // by chance, with a parallax the static scene does not have yet). 1: no cap.
  int parallax_grid_cols = 8;
  int parallax_grid_rows = 4;
  double parallax_cell_share = 0.125;
  int min_good_points = 50;
  double min_good_ratio = 0.9;
  double ambiguity_ratio = 0.75;

  // Throws InvalidArgument naming the bad field.
  void Check() const;
};

struct TwoViewResult {
  bool success = false;
  std::string reason;  // why not, when !success ("too few inliers", "low parallax", "ambiguous", ...)
  std::string model;   // "homography" or "fundamental" (empty when no model was selected)

  // Camera 1 is the world frame. |translation| = 1 (the scale of a monocular map is free); points use it.
  Rigid3d camera2_from_camera1;
  Points3d points;                 // one per input match, in camera 1; zero unless triangulated
  std::vector<bool> triangulated;  // one per input match

  // Diagnostics.
  double homography_score = 0.0;   // S_H
  double fundamental_score = 0.0;  // S_F
  double score_ratio = 0.0;        // S_H / (S_H + S_F)
  int homography_inliers = 0;
  int fundamental_inliers = 0;
  int num_inliers = 0;        // of the selected model
  int num_good = 0;           // good points of the best hypothesis
  int second_best_good = 0;   // good points of the second best hypothesis
  double parallax_deg = 0.0;  // the parallax_rank-th largest parallax of the best hypothesis (cells capped)
};

// `pixels1[i]` and `pixels2[i]` are the i-th match in images 1 and 2 (raw pixels: the camera's distortion is
// removed here). Never throws for scenes that cannot be initialized (success = false with a reason); throws
// InvalidArgument for bad options, a bad camera, mismatched sizes or non-finite pixels.
TwoViewResult InitializeTwoView(const std::vector<Eigen::Vector2d>& pixels1,
                                const std::vector<Eigen::Vector2d>& pixels2, const PinholeCamera& camera,
                                const TwoViewOptions& options);

}  // namespace semslam
