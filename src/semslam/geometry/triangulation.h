#pragma once
// Two-view triangulation from bearings and camera poses.

#include <optional>

#include "semslam/geometry/rigid3.h"

namespace semslam {

// Linear (DLT) triangulation of one point seen along `bearing1` from camera 1 and `bearing2` from
// camera 2 (bearings in each camera's frame, any length, z > 0 for points in front). Returns the point in
// the world frame, or nullopt when the rays are (nearly) parallel or the point is behind either camera.
std::optional<Eigen::Vector3d> TriangulatePoint(const Rigid3d& camera1_from_world, const Rigid3d& camera2_from_world,
                                                const Eigen::Vector3d& bearing1, const Eigen::Vector3d& bearing2);

// Angle in radians between the rays from two camera centres to a point (the parallax).
double TriangulationAngle(const Eigen::Vector3d& center1, const Eigen::Vector3d& center2,
                          const Eigen::Vector3d& point);

}  // namespace semslam
