#include "semslam/geo/georeference.h"

#include <algorithm>
#include <limits>

#include "semslam/core/error.h"
#include "semslam/geometry/alignment.h"

namespace semslam {

Sim3d EnuFromEnu(const EnuFrame& to, const EnuFrame& from) {
  // Both frames are local tangent planes of one ellipsoid: over a few kilometres one rigid transform, found
  // from points a kilometre apart.
  Points3d in_from, in_to;
  for (const Eigen::Vector3d& p :
       {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1000, 0, 0), Eigen::Vector3d(0, 1000, 0),
        Eigen::Vector3d(0, 0, 1000), Eigen::Vector3d(-1000, -1000, 0)}) {
    in_from.push_back(p);
    in_to.push_back(to.ToEnu(from.ToWgs84(p)));
  }
  const std::optional<Rigid3d> rigid = AlignRigid3(in_from, in_to);
  Require(rigid.has_value(), "two ENU frames could not be related");
  return Sim3d(*rigid);
}

Sim3d LevelFromCameraWorld() {
  Eigen::Matrix3d r;
  // Rows: east = x, north = z, up = -y.
  r << 1, 0, 0,  //
      0, 0, 1,   //
      0, -1, 0;
  return Sim3d(1.0, Eigen::Quaterniond(r), Eigen::Vector3d::Zero());
}

LocalCorrections::LocalCorrections(std::vector<Keyframe> keyframes) : keyframes_(std::move(keyframes)) {
  Require(!keyframes_.empty(), "local corrections need at least one keyframe");
  std::stable_sort(keyframes_.begin(), keyframes_.end(),
                   [](const Keyframe& a, const Keyframe& b) { return a.frame_index < b.frame_index; });
  enu_positions_.reserve(keyframes_.size());
  for (const Keyframe& k : keyframes_) {
    Require(k.map_position.allFinite() && std::isfinite(k.enu_from_map.scale) && k.enu_from_map.scale > 0 &&
                k.enu_from_map.translation.allFinite(),
            "local corrections: keyframe is not finite");
    enu_positions_.push_back(k.enu_from_map * k.map_position);
  }
}

size_t LocalCorrections::NearestInMap(const Eigen::Vector3d& map_point) const {
  size_t best = 0;
  double best_d = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < keyframes_.size(); ++i) {
    const double d = (keyframes_[i].map_position - map_point).squaredNorm();
    if (d < best_d) {
      best_d = d;
      best = i;
    }
  }
  return best;
}

size_t LocalCorrections::NearestInEnu(const Eigen::Vector3d& enu) const {
  size_t best = 0;
  double best_d = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < enu_positions_.size(); ++i) {
    const double d = (enu_positions_[i] - enu).squaredNorm();
    if (d < best_d) {
      best_d = d;
      best = i;
    }
  }
  return best;
}

Eigen::Vector3d LocalCorrections::MapToEnu(const Eigen::Vector3d& map_point) const {
  return keyframes_[NearestInMap(map_point)].enu_from_map * map_point;
}

Eigen::Vector3d LocalCorrections::EnuToMap(const Eigen::Vector3d& enu) const {
  return keyframes_[NearestInEnu(enu)].enu_from_map.Inverse() * enu;
}

Eigen::Vector3d LocalCorrections::FrameToEnu(size_t frame_index, const Eigen::Vector3d& map_point) const {
  const auto after = std::lower_bound(keyframes_.begin(), keyframes_.end(), frame_index,
                                      [](const Keyframe& k, size_t f) { return k.frame_index < f; });
  if (after == keyframes_.end()) return keyframes_.back().enu_from_map * map_point;
  if (after == keyframes_.begin() || after->frame_index == frame_index)
    return after->enu_from_map * map_point;
  const Keyframe& b = *after;
  const Keyframe& a = *std::prev(after);
  const double alpha =
      static_cast<double>(frame_index - a.frame_index) / static_cast<double>(b.frame_index - a.frame_index);
  return (1.0 - alpha) * (a.enu_from_map * map_point) + alpha * (b.enu_from_map * map_point);
}

}  // namespace semslam
