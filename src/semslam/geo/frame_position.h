#pragma once
// Positions of frames or keyframes in the SLAM map: the plain input of GPS alignment, landmark association
// and the topological map.

#include <cstddef>
#include <vector>

#include "semslam/geometry/eigen_types.h"

namespace semslam {

// A frame (or keyframe) position in the SLAM map.
struct FramePosition {
  size_t frame_index = 0;      // index in the sequence (sampling counts frames, not keyframes)
  long long keyframe_id = -1;  // the map's keyframe id when this is a keyframe (reported in outputs)
  double timestamp = 0.0;      // seconds, frame time base
  Eigen::Vector3d map_position = Eigen::Vector3d::Zero();  // camera centre, map frame
};

using FramePositions = std::vector<FramePosition>;

}  // namespace semslam
