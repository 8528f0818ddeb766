#pragma once
// Positions and poses of frames or keyframes in the SLAM map: the plain input of GPS alignment and fusion,
// landmark association and the topological map.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "semslam/geometry/eigen_types.h"
#include "semslam/geometry/rigid3.h"

namespace semslam {

// A frame (or keyframe) position in the SLAM map.
struct FramePosition {
  size_t frame_index = 0;                                  // index in the sequence (sampling counts frames)
  long long keyframe_id = -1;                              // the map's keyframe id when this is a keyframe
  double timestamp = 0.0;                                  // seconds, frame time base
  Eigen::Vector3d map_position = Eigen::Vector3d::Zero();  // camera centre, map frame
  std::uint32_t segment =
      0;  // the drive it belongs to, of several one after another (a merged map's sessions)
  // The camera's image-down axis (+y) in the map frame; zero when unknown. On a straight drive it gives the
  // roll about the track that GPS fixes on one line leave free (see GpsAlignmentOptions).
  Eigen::Vector3d camera_down = Eigen::Vector3d::Zero();
};

using FramePositions = std::vector<FramePosition>;

// A frame (or keyframe) pose in the SLAM map (the map frame is the SLAM "world").
struct FramePose {
  size_t frame_index = 0;
  long long keyframe_id = -1;
  double timestamp = 0.0;
  Rigid3d world_from_camera;  // map_from_camera; its translation is the camera centre
  std::uint32_t map_id = 0;   // which map of the atlas the pose is in (see map/map.h)
  bool predicted = false;     // not tracked: the motion model's prediction while tracking was lost
  std::uint32_t segment = 0;  // as FramePosition's

  FramePosition Position() const {
    FramePosition position{frame_index, keyframe_id, timestamp, world_from_camera.translation, segment};
    position.camera_down = world_from_camera.rotation * Eigen::Vector3d::UnitY();
    return position;
  }
};

inline FramePositions Positions(const std::vector<FramePose>& poses) {
  FramePositions out;
  out.reserve(poses.size());
  for (const FramePose& p : poses) out.push_back(p.Position());
  return out;
}

}  // namespace semslam
