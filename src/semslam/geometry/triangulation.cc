#include "semslam/geometry/triangulation.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace semslam {

std::optional<Eigen::Vector3d> TriangulatePoint(const Rigid3d& camera1_from_world, const Rigid3d& camera2_from_world,
                                                const Eigen::Vector3d& bearing1, const Eigen::Vector3d& bearing2) {
  const Eigen::Matrix3x4d p1 = camera1_from_world.ToMatrix();
  const Eigen::Matrix3x4d p2 = camera2_from_world.ToMatrix();
  // Cross-product form of x ~ P X, using bearings instead of pixels so that any z works.
  Eigen::Matrix4d a;
  const Eigen::Vector3d b1 = bearing1.normalized();
  const Eigen::Vector3d b2 = bearing2.normalized();
  a.row(0) = b1.x() * p1.row(2) - b1.z() * p1.row(0);
  a.row(1) = b1.y() * p1.row(2) - b1.z() * p1.row(1);
  a.row(2) = b2.x() * p2.row(2) - b2.z() * p2.row(0);
  a.row(3) = b2.y() * p2.row(2) - b2.z() * p2.row(1);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(a, Eigen::ComputeFullV);
  const Eigen::Vector4d x = svd.matrixV().col(3);
  if (std::abs(x.w()) < 1e-12) return std::nullopt;  // point at infinity: parallel rays
  const Eigen::Vector3d point = x.hnormalized();
  if (!point.allFinite()) return std::nullopt;
  if ((camera1_from_world * point).dot(b1) <= 0 || (camera2_from_world * point).dot(b2) <= 0) return std::nullopt;
  return point;
}

double TriangulationAngle(const Eigen::Vector3d& center1, const Eigen::Vector3d& center2,
                          const Eigen::Vector3d& point) {
  const Eigen::Vector3d r1 = point - center1;
  const Eigen::Vector3d r2 = point - center2;
  const double denom = r1.norm() * r2.norm();
  if (denom <= 0) return 0.0;
  return std::acos(std::clamp(r1.dot(r2) / denom, -1.0, 1.0));
}

}  // namespace semslam
