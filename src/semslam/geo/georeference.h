#pragma once
// How a SLAM map sits in the world: the ENU frame (around a WGS84 origin) and the similarity that maps map
// coordinates into it (from GPS alignment, or the pose-graph fusion's global part).

#include "semslam/geo/wgs84.h"
#include "semslam/geometry/sim3.h"

namespace semslam {

struct Georeference {
  EnuFrame enu_frame;
  Sim3d enu_from_map;

  Georeference(EnuFrame frame, const Sim3d& enu_from_map_in)
      : enu_frame(std::move(frame)), enu_from_map(enu_from_map_in) {}

  Eigen::Vector3d MapToEnu(const Eigen::Vector3d& map_point) const { return enu_from_map * map_point; }
  Eigen::Vector3d EnuToMap(const Eigen::Vector3d& enu) const { return enu_from_map.Inverse() * enu; }
  Wgs84 MapToWgs84(const Eigen::Vector3d& map_point) const { return enu_frame.ToWgs84(MapToEnu(map_point)); }
  Eigen::Vector3d Wgs84ToMap(const Wgs84& position) const { return EnuToMap(enu_frame.ToEnu(position)); }
  // Metres per map unit.
  double MetresPerMapUnit() const { return enu_from_map.scale; }
};

// The rotation that maps the first camera's frame (x right, y down, z forward: KITTI's world) to a level
// "east = right, north = forward, up = -down" frame: a stand-in for enu_from_map when there is no GPS, for
// top views and turn directions of a roughly level camera. Scale 1.
Sim3d LevelFromCameraWorld();

}  // namespace semslam
