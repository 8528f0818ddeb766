#pragma once
// How semslam's BRIEF sampling pattern was made, so that the table stored in orb_pattern_table.inc can be
// reproduced (tests/features/orb_pattern_test.cc checks that it is).
//
// Rublee et al. (ORB, ICCV 2011, section 4.3) observed that steered BRIEF's tests are correlated and have
// means far from 0.5, and picked 256 tests greedily: order the candidate tests by how close their mean is
// to 0.5 over many oriented training patches, then keep a test only if its correlation with every test
// already kept is below a threshold (raised until 256 are kept). We do the same with our own candidates
// (isotropic Gaussian point pairs, BRIEF's G II) and our own training patches (procedurally drawn
// images: shapes, edges, gradients, noise; see MakeSyntheticTrainingImage).

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "semslam/features/orb_descriptor.h"

namespace semslam {

// Deterministic pseudo-random numbers (splitmix64), identical on every platform.
class PatternRandom {
 public:
  explicit PatternRandom(std::uint64_t seed) : state_(seed) {}
  std::uint64_t Next();
  double Uniform();                // [0, 1)
  double Gaussian();               // N(0, 1), Box-Muller
  int UniformInt(int lo, int hi);  // [lo, hi]

 private:
  std::uint64_t state_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

// `count` distinct point pairs, each point drawn from N(0, sigma^2) per axis, rounded to pixels, kept
// within kBriefPatternRadius; pairs of coincident or adjacent points are rejected.
std::vector<BriefPair> GenerateGaussianPairs(std::uint64_t seed, int count, double sigma = 31.0 / 5.0);

// A grey image of random shapes (rectangles, polygons, ellipses, lines, blobs) on gradients, with noise
// and blur; deterministic for a seed.
cv::Mat MakeSyntheticTrainingImage(std::uint64_t seed, cv::Size size = {640, 480});

struct PatternLearningOptions {
  std::uint64_t seed = 2011;
  int num_candidates = 4000;       // Gaussian candidate tests
  double candidate_sigma = 9.0;    // their spread (pixels); wider than BRIEF G II (31/5) decorrelates better
  int num_images = 60;             // synthetic training images
  int keypoints_per_image = 500;   // strongest FAST corners (threshold 20) per image
  double start_correlation = 0.2;  // greedy threshold, raised by `correlation_step` until 256 tests are kept
  double correlation_step = 0.02;
  void Check() const;
};

struct PatternLearningStats {
  int training_patches = 0;
  double final_correlation_threshold = 0.0;
  double mean_abs_bias = 0.0;         // mean over kept tests of |mean - 0.5|
  double mean_abs_correlation = 0.0;  // mean |correlation| over pairs of kept tests
};

BriefPattern LearnBriefPattern(const PatternLearningOptions& options, PatternLearningStats* stats = nullptr);

// Statistics of a pattern on the training patches of `options` (for comparing patterns).
PatternLearningStats EvaluateBriefPattern(const BriefPattern& pattern, const PatternLearningOptions& options);

// The pattern as the lines of orb_pattern_table.inc ("{x1, y1, x2, y2},").
std::string FormatBriefPatternTable(const BriefPattern& pattern);

}  // namespace semslam
