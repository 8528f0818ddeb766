#include "semslam/place/bow_matching.h"

#include <climits>

#include "semslam/core/error.h"

namespace semslam {

void BowMatchOptions::Check() const {
  Require(ratio > 0.0f && ratio <= 1.0f, "BoW matching: ratio must be in (0, 1]");
  Require(max_distance >= 0 && max_distance <= 256, "BoW matching: max_distance must be in [0, 256]");
}

std::vector<int> MatchByBow(const FeatureSet& f1, const FeatureVector& fv1, const FeatureSet& f2,
                            const FeatureVector& fv2, const BowMatchOptions& options) {
  options.Check();
  std::vector<int> matches12(f1.size(), -1);
  std::vector<int> matches21(f2.size(), -1);
  std::vector<int> distance21(f2.size(), INT_MAX);
  ForEachSharedNode(fv1, fv2, [&](const std::vector<int>& indices1, const std::vector<int>& indices2) {
    for (const int i1 : indices1) {
      if (i1 < 0 || static_cast<size_t>(i1) >= f1.size()) continue;
      BestTwo best;
      for (const int i2 : indices2) {
        if (i2 < 0 || static_cast<size_t>(i2) >= f2.size()) continue;
        best.Offer(i2, HammingDistance(f1.descriptors[static_cast<size_t>(i1)],
                                       f2.descriptors[static_cast<size_t>(i2)]));
      }
      if (!best.found() || best.best > options.max_distance || !best.PassesRatio(options.ratio)) continue;
      const size_t j = static_cast<size_t>(best.best_index);
      if (matches21[j] >= 0) {
        if (distance21[j] <= best.best) continue;
        matches12[static_cast<size_t>(matches21[j])] = -1;
      }
      matches12[static_cast<size_t>(i1)] = best.best_index;
      matches21[j] = i1;
      distance21[j] = best.best;
    }
  });
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

}  // namespace semslam
