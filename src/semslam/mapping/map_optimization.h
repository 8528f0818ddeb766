#pragma once
// Bridges between the map and the optimizers: bundle-adjustment problems built from keyframes and map
// points, global BA applied to the map, and the Sim(3) refinement of a loop.

#include <atomic>
#include <utility>
#include <vector>

#include "semslam/geometry/sim3.h"
#include "semslam/map/map.h"
#include "semslam/optim/bundle_adjustment.h"

namespace semslam {

// One entry per problem observation: which keyframe saw which point.
struct ObservationRef {
  KeyFrame* keyframe = nullptr;
  MapPoint* point = nullptr;
};

// Adds poses for `keyframes` (free) and `fixed_keyframes` (fixed; a map's origin is always fixed), the
// `points`, and every observation of those points by those keyframes. Read lock.
void BuildBundleAdjustmentProblem(const std::vector<KeyFrame*>& keyframes,
                                  const std::vector<KeyFrame*>& fixed_keyframes,
                                  const std::vector<MapPoint*>& points, BundleAdjustmentProblem* problem,
                                  std::vector<ObservationRef>* refs);

// Writes optimized poses and points back (skipping bad ones) and drops outlier observations. Write lock.
void ApplyBundleAdjustment(Map& map, const BundleAdjustmentProblem& problem,
                           const BundleAdjustmentResult& result, const std::vector<KeyFrame*>& keyframes,
                           const std::vector<MapPoint*>& points, const std::vector<ObservationRef>& refs,
                           bool drop_outliers);

// Optimizes every keyframe and point of one map of the atlas in place. Write lock held by the caller.
void GlobalBundleAdjustment(Map& map, std::uint32_t map_id, int iterations, std::atomic<bool>* abort);

// Refines kf1_from_kf2 by the reprojection of matched points in both keyframes; outlier matches are
// cleared from `matches12`. Returns the inlier count. Read lock.
int RefineSim3(const KeyFrame& kf1, const KeyFrame& kf2, std::vector<MapPoint*>& matches12,
               Sim3d* kf1_from_kf2, double chi2_threshold, bool fix_scale);

}  // namespace semslam
