#pragma once
// ORB extraction (Rublee et al. 2011) spread evenly over the image and over a scale pyramid, as ORB-SLAM
// needs it (Mur-Artal et al. 2015, section III-A): FAST corners per pyramid level with a per-cell adaptive
// threshold, an even selection over each level, orientation by intensity centroid and steered binary tests
// with our own pattern. Parallel over levels and image strips (TBB).

#include <memory>
#include <opencv2/core.hpp>

#include "semslam/features/image_pyramid.h"
#include "semslam/features/orb_types.h"

namespace semslam {

enum class OrbDescriptorPattern {
  kSemslam,  // our learned pattern (orb_pattern.h); the default
  kOpenCv,   // computed by cv::ORB with OpenCV's standard pattern, for DBoW2 vocabularies such as ORBvoc.txt
};

struct OrbOptions {
  int num_features = 2000;  // per image, over all levels
  int num_levels = 8;
  float scale_factor = 1.2f;
  int initial_fast_threshold = 20;  // FAST threshold tried first in every cell
  int min_fast_threshold = 7;       // used in cells where the first gave no corner
  // Keypoints keep at least this distance (level pixels) from their level's border: the orientation disc
  // and the steered pattern must fit. >= kMinKeypointBorder (16).
  int edge_threshold = 16;
  int cell_size = 32;  // side (level pixels) of the adaptive-threshold cells
  // How num_features is shared among levels: level l gets scale_factor^(-exponent * l) of level 0's share.
  // 1 (by side length) keeps more features on the coarse levels than 2 (by area) and tracks better through
  // scale changes; on KITTI 07 it also gave a clearly lower trajectory error (0.25-0.30 m against 0.30-0.32
  // m).
  double level_share_exponent = 1.0;
  OrbDescriptorPattern pattern = OrbDescriptorPattern::kSemslam;
  bool parallel = true;  // spread the work over cores with TBB

  // Throws InvalidArgument naming the bad field.
  void Check() const;
};

class OrbExtractor {
 public:
  explicit OrbExtractor(const OrbOptions& options = {});
  ~OrbExtractor();
  OrbExtractor(const OrbExtractor&) = delete;
  OrbExtractor& operator=(const OrbExtractor&) = delete;

  const OrbOptions& options() const { return options_; }
  const PyramidGeometry& geometry() const { return geometry_; }

  // Features of an 8-bit grey image (3-channel BGR is converted). `mask` (optional, CV_8UC1, image size):
  // pixels where it is 0 get no keypoint (dynamic objects). Keypoint coordinates are level-0 pixels.
  // If `pyramid` is given, the image pyramid used is returned in it (for MatchStereo). Thread-safe: may be
  // called from several threads at once.
  FeatureSet Extract(const cv::Mat& image, const cv::Mat& mask = {}, ImagePyramid* pyramid = nullptr) const;

  // How many features each level is meant to get (see OrbOptions::level_share_exponent), summing to
  // num_features.
  std::vector<int> LevelBudgets() const;

 private:
  OrbOptions options_;
  PyramidGeometry geometry_;
  std::vector<int> level_budget_;
};

// Shares `total` among levels with the wanted shares `wanted` (summing to total) when level l has only
// `available[l]` candidates: levels short of their share give the rest to the others, in proportion to
// their shares. Exposed for tests.
std::vector<int> DistributeLevelBudgets(const std::vector<int>& wanted, const std::vector<int>& available);

// Picks up to `budget` of the candidates, evenly over the area [x0, x1) x [y0, y1): the area is cut into
// about `budget` square cells; every non-empty cell gives its strongest candidate, then its second
// strongest, and so on, strongest first within a round, until the budget is met. Returns the indices of
// the chosen candidates. Exposed for tests.
struct CornerCandidate {
  float x = 0, y = 0;
  float response = 0;
};
std::vector<int> SelectSpreadOut(const std::vector<CornerCandidate>& candidates, int budget, float x0,
                                 float y0, float x1, float y1);

}  // namespace semslam
