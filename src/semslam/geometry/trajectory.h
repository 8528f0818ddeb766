#pragma once
// A camera trajectory: time-stamped poses `world_from_camera`, in time order.

#include <vector>

#include "semslam/geometry/rigid3.h"

namespace semslam {

struct StampedPose {
  double timestamp = 0.0;  // seconds
  Rigid3d world_from_camera;
};

using Trajectory = std::vector<StampedPose>;

// Camera centres of a trajectory, in order.
Points3d Positions(const Trajectory& trajectory);
// Sum of distances between consecutive camera centres.
double PathLength(const Trajectory& trajectory);

}  // namespace semslam
