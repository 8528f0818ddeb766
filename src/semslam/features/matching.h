#pragma once
// Descriptor matching helpers: best / second-best search with the ratio test (Lowe 2004), the rotation
// consistency check of ORB-SLAM (Mur-Artal et al. 2015: the orientation differences of true matches agree,
// so matches outside the dominant bins of their histogram are dropped), and the window search of
// monocular initialization.

#include <climits>
#include <vector>

#include "semslam/features/feature_grid.h"
#include "semslam/features/orb_types.h"

namespace semslam {

// Hamming thresholds (of 256 bits) used across matching.
struct MatcherThresholds {
  static constexpr int kHigh = 100;  // loose: projection matching with a good pose prior
  static constexpr int kLow = 50;    // strict: matching without geometric prior
};

// The two smallest distances seen, and which candidate gave the smallest.
struct BestTwo {
  int best_index = -1;
  int best = INT_MAX;
  int second = INT_MAX;

  void Offer(int index, int distance) {
    if (distance < best) {
      second = best;
      best = distance;
      best_index = index;
    } else if (distance < second) {
      second = distance;
    }
  }
  bool found() const { return best_index >= 0; }
  // best < ratio * second (true when there was no second candidate).
  bool PassesRatio(float ratio) const {
    return second == INT_MAX || static_cast<float>(best) < ratio * static_cast<float>(second);
  }
};

// Best two of `descriptors[c]` for c in `candidates` against `query`.
template <typename IndexRange>
BestTwo FindBestTwo(const Descriptor& query, const IndexRange& candidates,
                    const std::vector<Descriptor>& descriptors) {
  BestTwo result;
  for (const auto c : candidates) {
    result.Offer(static_cast<int>(c), HammingDistance(query, descriptors[static_cast<size_t>(c)]));
  }
  return result;
}

// Histogram of orientation differences of tentative matches. Add() every match with its angle difference
// (degrees, any range); afterwards Consistent() / Inconsistent() give the match ids inside / outside the
// (up to) three dominant bins. A second or third bin counts as dominant only if it holds at least
// `min_fraction` of the largest bin's matches.
class RotationHistogram {
 public:
  explicit RotationHistogram(int num_bins = 30, float min_fraction = 0.1f);

  void Add(float angle_difference_deg, int match_id);
  std::vector<int> Consistent() const;
  std::vector<int> Inconsistent() const;
  // Indices of the dominant bins (largest first).
  std::vector<int> DominantBins() const;
  int BinOf(float angle_difference_deg) const;

 private:
  int num_bins_;
  float min_fraction_;
  std::vector<std::vector<int>> bins_;
};

struct InitializationMatchOptions {
  float ratio = 0.9f;                          // nearest / second-nearest
  int max_distance = MatcherThresholds::kLow;  // Hamming
  bool check_orientation = true;
  int max_level = 0;  // only keypoints of levels [0, max_level] in both frames
  // A keypoint of level l is matched to levels [l - d, l + d] (the scale changes as the camera moves on).
  int max_level_difference = 0;
  void Check() const;
};

// Monocular initialization: for every keypoint i of `f1` (its level <= max_level), searches `f2`'s keypoints
// (level <= max_level) within a square window of half-side `window` around prior_positions[i] (where it was
// last seen), with the ratio test and a rotation-consistency check; each f2 keypoint keeps only its best
// f1 match. Returns matches12: for each f1 keypoint the index of its f2 match or -1.
// prior_positions.size() must equal f1.size().
std::vector<int> MatchForInitialization(const FeatureSet& f1, const FeatureSet& f2,
                                        const std::vector<Eigen::Vector2f>& prior_positions, float window,
                                        const InitializationMatchOptions& options = {});
// The same with a prebuilt grid of f2.
std::vector<int> MatchForInitialization(const FeatureSet& f1, const FeatureSet& f2, const FeatureGrid& grid2,
                                        const std::vector<Eigen::Vector2f>& prior_positions, float window,
                                        const InitializationMatchOptions& options = {});

struct BruteForceMatchOptions {
  float ratio = 0.8f;
  int max_distance = MatcherThresholds::kLow;
  bool mutual = true;  // keep i <-> j only if each is the other's nearest
  void Check() const;
};
// Exhaustive matching (for tests, tools and small sets): matches12 as above.
std::vector<int> MatchBruteForce(const FeatureSet& f1, const FeatureSet& f2,
                                 const BruteForceMatchOptions& options = {});

}  // namespace semslam
