#pragma once
// Gap links (map/map.h) in a bundle adjustment. The two sides of a loss in tracking share no points, so
// nothing the images hold fixes where one lies relative to the other: a BA over a window on one side swings
// that side about wherever its other points tie it, and undoes what the loop correction's pose graph did at
// the gap. A pose prior holds each gap link's ends as the map has them when the BA starts.

#include <unordered_set>
#include <vector>

#include "semslam/map/map.h"
#include "semslam/optim/bundle_adjustment.h"

namespace semslam {

// The good keyframes standing for the ends of the map's gap links (read lock).
std::unordered_set<const KeyFrame*> GapLinkEnds(const Map& map);

// Adds a pose prior to `problem` (poses in the order of `keyframes`) for each gap link with an end among
// `keyframes`; an end the problem lacks is appended to both, fixed, as the map holds it. The prior's target
// is the ends' relative pose in the map now; its sigmas are 5 % of their distance and 1 degree. Read lock.
void AddGapLinkPriors(const Map& map, std::vector<KeyFrame*>* keyframes, BundleAdjustmentProblem* problem);

}  // namespace semslam
