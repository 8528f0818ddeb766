#include "semslam/map/map_validation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "semslam/core/error.h"

namespace semslam {

namespace {

[[noreturn]] void Fail(const std::filesystem::path& file, const std::string& record, const std::string& message) {
  throw InputError(file, fmt::format("{}: {}", record, message));
}

}  // namespace

void CheckKeyFrameRecord(const KeyFrameRecordCheck& k, const std::filesystem::path& file) {
  const std::string record = fmt::format("keyframe {}", k.id);
  if (!std::isfinite(k.timestamp)) Fail(file, record, fmt::format("timestamp {} is not finite", k.timestamp));
  const PinholeCamera& c = *k.camera;
  constexpr int kMaxImageSide = 1 << 15;
  if (c.width <= 0 || c.height <= 0 || c.width > kMaxImageSide || c.height > kMaxImageSide) {
    Fail(file, record, fmt::format("camera image size {}x{} is not plausible", c.width, c.height));
  }
  if (!(std::isfinite(c.fx) && c.fx > 0 && std::isfinite(c.fy) && c.fy > 0 && std::isfinite(c.cx) &&
        std::isfinite(c.cy)) ||
      std::abs(c.cx) > 4.0 * kMaxImageSide || std::abs(c.cy) > 4.0 * kMaxImageSide || c.fx > 1e6 || c.fy > 1e6) {
    Fail(file, record, fmt::format("camera intrinsics fx={} fy={} cx={} cy={} are not plausible", c.fx, c.fy,
                                   c.cx, c.cy));
  }
  if (!std::isfinite(k.baseline) || k.baseline < 0 || k.baseline > 1e3) {
    Fail(file, record, fmt::format("stereo baseline {} is not plausible", k.baseline));
  }
  if (k.image_width != c.width || k.image_height != c.height) {
    Fail(file, record, fmt::format("features of a {}x{} image for a {}x{} camera", k.image_width, k.image_height,
                                   c.width, c.height));
  }
  // Keypoints lie in the (undistorted) image; a generous margin for undistortion.
  const double margin_x = c.width, margin_y = c.height;
  for (size_t i = 0; i < k.keypoints->size(); ++i) {
    const Eigen::Vector2f& p = (*k.keypoints)[i].pixel;
    if (!p.allFinite() || p.x() < -margin_x || p.x() > c.width + margin_x || p.y() < -margin_y ||
        p.y() > c.height + margin_y) {
      Fail(file, record, fmt::format("keypoint {} at ({}, {}) lies outside the {}x{} image", i, p.x(), p.y(),
                                     c.width, c.height));
    }
  }
  for (const std::vector<float>* values : {k.right_u, k.depth}) {
    for (size_t i = 0; i < values->size(); ++i) {
      const float v = (*values)[i];
      if (!std::isfinite(v) || std::abs(v) > kMaxMapCoordinateM) {
        Fail(file, record, fmt::format("stereo value {} of keypoint {} is not plausible", v, i));
      }
    }
  }
  if (k.gps_enu && (!k.gps_enu->allFinite() || k.gps_enu->cwiseAbs().maxCoeff() > kMaxMapCoordinateM)) {
    Fail(file, record, "GPS position is not finite or too far away");
  }
  if (!std::isfinite(k.gps_sigma_m) || k.gps_sigma_m < 0) {
    Fail(file, record, fmt::format("GPS sigma {} is not plausible", k.gps_sigma_m));
  }
}

void CheckPointRecord(std::uint64_t id, const Eigen::Vector3d& position, int visible, int found,
                      const std::filesystem::path& file) {
  const std::string record = fmt::format("map point {}", id);
  if (!position.allFinite() || position.cwiseAbs().maxCoeff() > kMaxMapCoordinateM) {
    Fail(file, record, fmt::format("position ({}, {}, {}) is not finite or too far away", position.x(),
                                   position.y(), position.z()));
  }
  if (visible < 0 || found < 0) {
    Fail(file, record, fmt::format("negative visibility counts ({} visible, {} found)", visible, found));
  }
}

std::vector<std::uint64_t> RepairSpanningTree(std::unordered_map<std::uint64_t, std::uint64_t>& parent_of,
                                              const std::filesystem::path& file) {
  std::vector<std::uint64_t> ids;
  ids.reserve(parent_of.size());
  for (const auto& [id, parent] : parent_of) {
    if (parent != kNoParent && !parent_of.count(parent)) {
      Fail(file, fmt::format("keyframe {}", id), fmt::format("parent {} does not exist", parent));
    }
    ids.push_back(id);
  }
  std::sort(ids.begin(), ids.end());
  std::vector<std::uint64_t> made_roots;
  // Keyframes whose path to a root is known to be sound.
  std::unordered_set<std::uint64_t> rooted;
  for (const std::uint64_t start : ids) {
    std::vector<std::uint64_t> path;
    std::unordered_set<std::uint64_t> on_path;
    for (std::uint64_t id = start; id != kNoParent && !rooted.count(id); id = parent_of.at(id)) {
      if (!on_path.insert(id).second) {
        // A tree grows from older keyframes to younger ones: the link from the cycle's oldest keyframe to a
        // younger one is the one that went wrong. Without it, every keyframe on the path leads to that one.
        const auto cycle = std::find(path.begin(), path.end(), id);
        const std::uint64_t oldest = *std::min_element(cycle, path.end());
        parent_of[oldest] = kNoParent;
        made_roots.push_back(oldest);
        break;
      }
      path.push_back(id);
    }
    rooted.insert(path.begin(), path.end());
  }
  return made_roots;
}

}  // namespace semslam
