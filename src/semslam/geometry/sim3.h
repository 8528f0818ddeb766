#pragma once
// Similarity transforms (Sim(3)): x' = scale * R x + t. Used for monocular maps, whose scale is
// unobservable, and to tie a map to a metric frame (`enu_from_map`).

#include "semslam/geometry/rigid3.h"

namespace semslam {

struct Sim3d {
  double scale = 1.0;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Sim3d() = default;
  Sim3d(double s, const Eigen::Quaterniond& r, const Eigen::Vector3d& t)
      : scale(s), rotation(r.normalized()), translation(t) {}
  explicit Sim3d(const Rigid3d& rigid) : scale(1.0), rotation(rigid.rotation), translation(rigid.translation) {}

  Eigen::Matrix3x4d ToMatrix() const;
  Sim3d Inverse() const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const { return scale * (rotation * point) + translation; }
  Sim3d operator*(const Sim3d& other) const;

  // Maps a pose `src_from_camera` to `tgt_from_camera` (this = tgt_from_src). The camera keeps its
  // metric-free rotation; only its position is scaled.
  Rigid3d TransformPose(const Rigid3d& src_from_camera) const;
  // The rigid part, dropping the scale.
  Rigid3d Rigid() const { return Rigid3d(rotation, translation); }
};

}  // namespace semslam
