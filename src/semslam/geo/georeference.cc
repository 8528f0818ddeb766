#include "semslam/geo/georeference.h"

namespace semslam {

Sim3d LevelFromCameraWorld() {
  Eigen::Matrix3d r;
  // Rows: east = x, north = z, up = -y.
  r << 1, 0, 0,  //
      0, 0, 1,   //
      0, -1, 0;
  return Sim3d(1.0, Eigen::Quaterniond(r), Eigen::Vector3d::Zero());
}

}  // namespace semslam
