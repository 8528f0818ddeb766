#pragma once
// Queries over the keyframe graph: the spanning tree, loop links and strong covisibility that the essential
// graph optimizes.

#include "semslam/map/keyframe.h"

namespace semslam {

// The length in map units of the shortest chain of links between two keyframes of one map, each link as
// long as the distance between its keyframes' centres. Links: parent and children, loop edges, and
// covisibility of at least `min_covisibility_weight` shared points. This is the odometry whose drift a loop
// between the two can correct: a revisit tracked in the map, a loop or a merge already closed shortens it.
// Infinity when no chain joins them. Call under the map's read lock.
double KeyFrameGraphDistance(const KeyFrame& from, const KeyFrame& to, int min_covisibility_weight);

}  // namespace semslam
