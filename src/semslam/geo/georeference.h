#pragma once
// How a SLAM map sits in the world: the ENU frame (around a WGS84 origin) and the similarity that maps map
// coordinates into it (from GPS alignment), optionally refined by per-keyframe corrections (the pose-graph
// fusion's result: a monocular map whose scale drifts is not one similarity away from ENU).

#include <memory>
#include <vector>

#include "semslam/geo/wgs84.h"
#include "semslam/geometry/sim3.h"

namespace semslam {

// Per-keyframe similarities enu_from_map (fused keyframe pose * map keyframe pose^-1). A map point goes
// through the correction of its nearest keyframe (map frame); a frame's camera through the blend of the
// keyframes before and after it in frame order.
class LocalCorrections {
 public:
  struct Keyframe {
    size_t frame_index = 0;
    Eigen::Vector3d map_position = Eigen::Vector3d::Zero();  // camera centre in the map
    Sim3d enu_from_map;
  };
  // `keyframes` in any order (sorted by frame index here); at least one. Throws InvalidArgument otherwise.
  explicit LocalCorrections(std::vector<Keyframe> keyframes);

  const std::vector<Keyframe>& keyframes() const { return keyframes_; }
  // Index of the keyframe nearest to a map point / an ENU point (through each keyframe's own correction).
  size_t NearestInMap(const Eigen::Vector3d& map_point) const;
  size_t NearestInEnu(const Eigen::Vector3d& enu) const;
  Eigen::Vector3d MapToEnu(const Eigen::Vector3d& map_point) const;
  Eigen::Vector3d EnuToMap(const Eigen::Vector3d& enu) const;
  // A point seen from frame `frame_index` (e.g. its camera centre): the corrections of the keyframes before
  // and after it, blended linearly in frame index (the nearest one outside their range).
  Eigen::Vector3d FrameToEnu(size_t frame_index, const Eigen::Vector3d& map_point) const;

 private:
  std::vector<Keyframe> keyframes_;
  Points3d enu_positions_;
};

struct Georeference {
  EnuFrame enu_frame;
  Sim3d enu_from_map;                             // the global similarity (scale = metres per map unit)
  std::shared_ptr<const LocalCorrections> local;  // optional refinement

  Georeference(EnuFrame frame, const Sim3d& enu_from_map_in,
               std::shared_ptr<const LocalCorrections> local_in = nullptr)
      : enu_frame(std::move(frame)), enu_from_map(enu_from_map_in), local(std::move(local_in)) {}

  Eigen::Vector3d MapToEnu(const Eigen::Vector3d& map_point) const {
    return local ? local->MapToEnu(map_point) : enu_from_map * map_point;
  }
  Eigen::Vector3d EnuToMap(const Eigen::Vector3d& enu) const {
    return local ? local->EnuToMap(enu) : enu_from_map.Inverse() * enu;
  }
  // Into the map near `map_anchor` (e.g. a keyframe's centre): through that place's correction. Where the
  // trajectory passes a place twice without a loop closure, the map holds it twice; the anchor says which.
  Eigen::Vector3d EnuToMapAt(const Eigen::Vector3d& enu, const Eigen::Vector3d& map_anchor) const {
    return local ? local->keyframes()[local->NearestInMap(map_anchor)].enu_from_map.Inverse() * enu
                 : enu_from_map.Inverse() * enu;
  }
  // A point of frame `frame_index` (its camera centre for a trajectory): smooth along the trajectory.
  Eigen::Vector3d FrameToEnu(size_t frame_index, const Eigen::Vector3d& map_point) const {
    return local ? local->FrameToEnu(frame_index, map_point) : enu_from_map * map_point;
  }
  Wgs84 MapToWgs84(const Eigen::Vector3d& map_point) const { return enu_frame.ToWgs84(MapToEnu(map_point)); }
  Eigen::Vector3d Wgs84ToMap(const Wgs84& position) const { return EnuToMap(enu_frame.ToEnu(position)); }
  // Metres per map unit (of the global similarity).
  double MetresPerMapUnit() const { return enu_from_map.scale; }
};

// ENU of `to` from ENU of `from`: a rigid transform (scale 1), exact to millimetres over a few kilometres.
Sim3d EnuFromEnu(const EnuFrame& to, const EnuFrame& from);

// The rotation that maps the first camera's frame (x right, y down, z forward: KITTI's world) to a level
// "east = right, north = forward, up = -down" frame: a stand-in for enu_from_map when there is no GPS, for
// top views and turn directions of a roughly level camera. Scale 1.
Sim3d LevelFromCameraWorld();

}  // namespace semslam
