#include "semslam/geometry/trajectory.h"

namespace semslam {

Points3d Positions(const Trajectory& trajectory) {
  Points3d positions;
  positions.reserve(trajectory.size());
  for (const auto& pose : trajectory) positions.push_back(pose.world_from_camera.translation);
  return positions;
}

double PathLength(const Trajectory& trajectory) {
  double length = 0.0;
  for (size_t i = 1; i < trajectory.size(); ++i) {
    length += (trajectory[i].world_from_camera.translation - trajectory[i - 1].world_from_camera.translation).norm();
  }
  return length;
}

}  // namespace semslam
