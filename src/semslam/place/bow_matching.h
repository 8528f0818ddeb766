#pragma once
// Descriptor matching between two images accelerated by their direct indices (Galvez-Lopez & Tardos 2012,
// section V; used by ORB-SLAM for relocalization and loop closing): only features under the same
// vocabulary node are compared.

#include <vector>

#include "semslam/features/matching.h"
#include "semslam/features/orb_types.h"
#include "semslam/place/bow_vector.h"

namespace semslam {

struct BowMatchOptions {
  float ratio = 0.75f;                         // nearest / second-nearest within the node
  int max_distance = MatcherThresholds::kLow;  // Hamming
  bool check_orientation = true;               // rotation-consistency histogram
  void Check() const;
};

// Calls fn(indices1, indices2) for every node present in both direct indices, in node order.
template <typename Fn>
void ForEachSharedNode(const FeatureVector& a, const FeatureVector& b, Fn&& fn) {
  auto ia = a.begin();
  auto ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (ia->first == ib->first) {
      fn(ia->second, ib->second);
      ++ia;
      ++ib;
    } else if (ia->first < ib->first) {
      ia = a.lower_bound(ib->first);
    } else {
      ib = b.lower_bound(ia->first);
    }
  }
}

// One-to-one matches between two feature sets through their direct indices (made by the same vocabulary at
// the same level). Returns matches12: for each keypoint of f1 the index of its match in f2, or -1. Each f2
// keypoint keeps only its best f1 match.
std::vector<int> MatchByBow(const FeatureSet& f1, const FeatureVector& fv1, const FeatureSet& f2,
                            const FeatureVector& fv2, const BowMatchOptions& options = {});

}  // namespace semslam
