#pragma once
// The left grey camera of KITTI odometry 07 (calib.txt P0), for tests and benchmarks on synthetic geometry.

#include "semslam/geometry/camera.h"

namespace semslam {

inline PinholeCamera KittiCamera() {
  PinholeCamera camera;
  camera.width = 1241;
  camera.height = 376;
  camera.fx = camera.fy = 718.856;
  camera.cx = 607.1928;
  camera.cy = 185.2157;
  return camera;
}

}  // namespace semslam
