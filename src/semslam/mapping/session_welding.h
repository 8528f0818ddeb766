#pragma once

// Drives merged into one map share points only where a merge or a loop joined them: along the streets between
// those places each drive keeps its own points and its own drift, and the final bundle adjustment has nothing
// to hold the drives to each other there. Welding fuses the points of every keyframe with those of other
// drives' keyframes beside it (same place, same heading), so that the adjustment ties the drives along every
// street they share.

#include <cstdint>

#include "semslam/map/map.h"

namespace semslam {

struct SessionWeldingOptions {
  // Keyframes of another drive this near, in units of the drive's median keyframe spacing, are its
  // neighbours.
  double neighbour_radius_spacings = 3.0;
  // ...when their viewing directions are this close (degrees).
  double max_heading_difference_deg = 30.0;
  // The nearest neighbours of each keyframe whose points it is offered.
  int max_neighbours = 5;
  // Search radius of the projection, in pixels at the keypoint's pyramid level (map/map_matcher.h's Fuse).
  float fuse_radius_px = 3.0f;

  void Check() const;
};

struct SessionWeldingSummary {
  size_t keyframes = 0;           // keyframes with a neighbour of another drive
  size_t fused_observations = 0;  // keypoints that took a point of another drive
};

// Welds the drives (sessions) of map `map_id`. The map's write lock is held by the caller.
SessionWeldingSummary WeldSessions(Map& map, std::uint32_t map_id, const SessionWeldingOptions& options = {});

}  // namespace semslam
