#include "semslam/geometry/sim3.h"

namespace semslam {

Eigen::Matrix3x4d Sim3d::ToMatrix() const {
  Eigen::Matrix3x4d m;
  m.leftCols<3>() = scale * rotation.toRotationMatrix();
  m.col(3) = translation;
  return m;
}

Sim3d Sim3d::Inverse() const {
  const Eigen::Quaterniond inv = rotation.conjugate();
  return Sim3d(1.0 / scale, inv, -(inv * translation) / scale);
}

Sim3d Sim3d::operator*(const Sim3d& other) const {
  return Sim3d(scale * other.scale, rotation * other.rotation, scale * (rotation * other.translation) + translation);
}

Rigid3d Sim3d::TransformPose(const Rigid3d& src_from_camera) const {
  return Rigid3d(rotation * src_from_camera.rotation, (*this) * src_from_camera.translation);
}

}  // namespace semslam
