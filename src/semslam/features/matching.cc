#include "semslam/features/matching.h"

#include <algorithm>
#include <cmath>

#include "semslam/core/error.h"

namespace semslam {

RotationHistogram::RotationHistogram(int num_bins, float min_fraction)
    : num_bins_(num_bins), min_fraction_(min_fraction) {
  Require(num_bins >= 1, "RotationHistogram: need at least one bin");
  Require(min_fraction >= 0.0f && min_fraction <= 1.0f, "RotationHistogram: min_fraction must be in [0, 1]");
  bins_.resize(static_cast<size_t>(num_bins));
}

int RotationHistogram::BinOf(float angle_difference_deg) const {
  if (!std::isfinite(angle_difference_deg)) return 0;
  float a = std::fmod(angle_difference_deg, 360.0f);
  if (a < 0.0f) a += 360.0f;
  const int bin = static_cast<int>(a * static_cast<float>(num_bins_) / 360.0f);
  return std::clamp(bin, 0, num_bins_ - 1);
}

void RotationHistogram::Add(float angle_difference_deg, int match_id) {
  bins_[static_cast<size_t>(BinOf(angle_difference_deg))].push_back(match_id);
}

std::vector<int> RotationHistogram::DominantBins() const {
  std::vector<int> order(static_cast<size_t>(num_bins_));
  for (int b = 0; b < num_bins_; ++b) order[static_cast<size_t>(b)] = b;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return bins_[static_cast<size_t>(a)].size() > bins_[static_cast<size_t>(b)].size();
  });
  std::vector<int> dominant;
  const size_t top = bins_[static_cast<size_t>(order[0])].size();
  if (top == 0) return dominant;
  dominant.push_back(order[0]);
  for (size_t k = 1; k < std::min<size_t>(3, order.size()); ++k) {
    const size_t count = bins_[static_cast<size_t>(order[k])].size();
    if (count == 0 || static_cast<float>(count) < min_fraction_ * static_cast<float>(top)) break;
    dominant.push_back(order[k]);
  }
  return dominant;
}

std::vector<int> RotationHistogram::Consistent() const {
  std::vector<int> out;
  for (const int b : DominantBins()) {
    const auto& bin = bins_[static_cast<size_t>(b)];
    out.insert(out.end(), bin.begin(), bin.end());
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<int> RotationHistogram::Inconsistent() const {
  const std::vector<int> dominant = DominantBins();
  std::vector<int> out;
  for (int b = 0; b < num_bins_; ++b) {
    if (std::find(dominant.begin(), dominant.end(), b) != dominant.end()) continue;
    const auto& bin = bins_[static_cast<size_t>(b)];
    out.insert(out.end(), bin.begin(), bin.end());
  }
  std::sort(out.begin(), out.end());
  return out;
}

void InitializationMatchOptions::Check() const {
  Require(ratio > 0.0f && ratio <= 1.0f, "initialization matching: ratio must be in (0, 1]");
  Require(max_distance >= 0 && max_distance <= 256,
          "initialization matching: max_distance must be in [0, 256]");
  Require(max_level >= 0 && max_level_difference >= 0,
          "initialization matching: max_level and max_level_difference must be >= 0");
}

std::vector<int> MatchForInitialization(const FeatureSet& f1, const FeatureSet& f2,
                                        const std::vector<Eigen::Vector2f>& prior_positions, float window,
                                        const InitializationMatchOptions& options) {
  const FeatureGrid grid(f2);
  return MatchForInitialization(f1, f2, grid, prior_positions, window, options);
}

std::vector<int> MatchForInitialization(const FeatureSet& f1, const FeatureSet& f2, const FeatureGrid& grid2,
                                        const std::vector<Eigen::Vector2f>& prior_positions, float window,
                                        const InitializationMatchOptions& options) {
  options.Check();
  Require(prior_positions.size() == f1.size(),
          "MatchForInitialization: need one prior position per f1 keypoint");
  Require(window >= 0.0f, "MatchForInitialization: window must be >= 0");
  std::vector<int> matches12(f1.size(), -1);
  std::vector<int> matches21(f2.size(), -1);
  std::vector<int> distance21(f2.size(), INT_MAX);
  std::vector<int> candidates;
  for (size_t i = 0; i < f1.size(); ++i) {
    const int level = f1.keypoints[i].level;
    if (level > options.max_level) continue;
    const Eigen::Vector2f& prior = prior_positions[i];
    grid2.FeaturesInArea(prior.x(), prior.y(), window, std::max(0, level - options.max_level_difference),
                         std::min(options.max_level, level + options.max_level_difference), candidates);
    if (candidates.empty()) continue;
    const BestTwo best = FindBestTwo(f1.descriptors[i], candidates, f2.descriptors);
    if (!best.found() || best.best > options.max_distance || !best.PassesRatio(options.ratio)) continue;
    const size_t j = static_cast<size_t>(best.best_index);
    if (matches21[j] >= 0) {
      if (distance21[j] <= best.best) continue;  // the earlier claim is at least as good
      matches12[static_cast<size_t>(matches21[j])] = -1;
    }
    matches12[i] = best.best_index;
    matches21[j] = static_cast<int>(i);
    distance21[j] = best.best;
  }
  if (options.check_orientation) {
    RotationHistogram histogram;
    for (size_t i = 0; i < f1.size(); ++i) {
      if (matches12[i] < 0) continue;
      histogram.Add(f1.keypoints[i].angle_deg - f2.keypoints[static_cast<size_t>(matches12[i])].angle_deg,
                    static_cast<int>(i));
    }
    for (const int i : histogram.Inconsistent()) matches12[static_cast<size_t>(i)] = -1;
  }
  return matches12;
}

void BruteForceMatchOptions::Check() const {
  Require(ratio > 0.0f && ratio <= 1.0f, "brute-force matching: ratio must be in (0, 1]");
  Require(max_distance >= 0 && max_distance <= 256, "brute-force matching: max_distance must be in [0, 256]");
}

std::vector<int> MatchBruteForce(const FeatureSet& f1, const FeatureSet& f2,
                                 const BruteForceMatchOptions& options) {
  options.Check();
  std::vector<int> matches12(f1.size(), -1);
  for (size_t i = 0; i < f1.size(); ++i) {
    BestTwo best;
    for (size_t j = 0; j < f2.size(); ++j) {
      best.Offer(static_cast<int>(j), HammingDistance(f1.descriptors[i], f2.descriptors[j]));
    }
    if (best.found() && best.best <= options.max_distance && best.PassesRatio(options.ratio)) {
      matches12[i] = best.best_index;
    }
  }
  if (options.mutual) {
    for (size_t i = 0; i < f1.size(); ++i) {
      const int j = matches12[i];
      if (j < 0) continue;
      int best_i = -1, best_d = INT_MAX;
      for (size_t k = 0; k < f1.size(); ++k) {
        const int d = HammingDistance(f1.descriptors[k], f2.descriptors[static_cast<size_t>(j)]);
        if (d < best_d) {
          best_d = d;
          best_i = static_cast<int>(k);
        }
      }
      if (best_i != static_cast<int>(i)) matches12[i] = -1;
    }
  }
  return matches12;
}

}  // namespace semslam
