#pragma once
// Matching the ORB features of a rectified stereo pair (Mur-Artal & Tardos 2017, section III-A): for each
// left keypoint, the most similar right keypoint on the same rows (a band that grows with the pyramid
// level) within the disparity range, then sub-pixel refinement of the right u coordinate by correlating a
// patch (sum of absolute differences of mean-removed intensities) along the row on the keypoint's pyramid
// level and fitting a parabola through the three costs around the minimum; matches whose correlation cost
// is far above the median are dropped.

#include <opencv2/core.hpp>
#include <vector>

#include "semslam/features/image_pyramid.h"
#include "semslam/features/matching.h"
#include "semslam/features/orb_types.h"
#include "semslam/geometry/camera.h"

namespace semslam {

struct StereoMatchOptions {
  // Nearest depth searched, in metres; <= 0 means one baseline (the disparity limit is then fx).
  double min_depth = 0.0;
  int max_descriptor_distance = (MatcherThresholds::kHigh + MatcherThresholds::kLow) / 2;
  // Nearest / second-nearest descriptor distance among the row candidates (1 turns the test off). Repeated
  // structure (windows, fences) gives near ties; the test drops those ambiguous matches.
  float ratio = 0.9f;
  float row_band = 2.0f;         // rows searched: |v_right - v_left| <= row_band * scale(level)
  int max_level_difference = 1;  // right keypoint's level within this of the left's
  int patch_half_size = 5;       // correlation patch (2h+1)^2 on the keypoint's level
  int search_half_range = 5;     // level pixels searched each side of the descriptor match
  float outlier_factor = 2.1f;   // drop matches whose cost exceeds this times the median cost
  // Sub-pixel offset from the costs c(-1), c(0), c(+1) around the minimum: a parabola through them, or two
  // lines of opposite slope ("equiangular", Shimizu & Okutomi 2005), the exact model for SAD costs.
  enum class SubpixelFit { kParabola, kEquiangular };
  SubpixelFit subpixel_fit = SubpixelFit::kEquiangular;
  bool parallel = true;
  void Check() const;
};

// Per left keypoint: u in the right image (level-0 pixels, sub-pixel) and depth along the left camera's
// z axis, both < 0 when unmatched.
struct StereoMatches {
  std::vector<float> right_u;
  std::vector<float> depth;
  int num_matched = 0;
};

// The images are the rectified left and right level-0 images the features were extracted from.
StereoMatches MatchStereo(const FeatureSet& left, const FeatureSet& right, const cv::Mat& left_image,
                          const cv::Mat& right_image, const StereoRig& rig,
                          const StereoMatchOptions& options = {});
// The same with the pyramids the extractor built (OrbExtractor::Extract's `pyramid` output): saves
// rebuilding them.
StereoMatches MatchStereo(const FeatureSet& left, const FeatureSet& right, const ImagePyramid& left_pyramid,
                          const ImagePyramid& right_pyramid, const StereoRig& rig,
                          const StereoMatchOptions& options = {});

}  // namespace semslam
