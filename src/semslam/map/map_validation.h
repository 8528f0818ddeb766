#pragma once
// Content checks of a map file beyond its checksum. A checksum only says that the bytes are those that were
// written; a map written by a buggy or foreign tool, or edited, can still hold contradictions that would crash
// or silently mislead tracking: a NaN timestamp, a keypoint at 1e30 pixels, a camera with a zero-sized image,
// a keyframe that is its own ancestor in the spanning tree, an observation of a keypoint that does not exist.
// Each check throws InputError naming the file, the record (keyframe or point id) and what is wrong.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <unordered_map>
#include <vector>

#include "semslam/features/orb_types.h"
#include "semslam/geometry/camera.h"
#include "semslam/geometry/eigen_types.h"

namespace semslam {

// What a keyframe record holds before a KeyFrame is built from it.
struct KeyFrameRecordCheck {
  std::uint64_t id = 0;
  double timestamp = 0.0;
  const PinholeCamera* camera = nullptr;
  double baseline = 0.0;
  int image_width = 0, image_height = 0;
  const std::vector<Keypoint>* keypoints = nullptr;
  const std::vector<float>* right_u = nullptr;
  const std::vector<float>* depth = nullptr;
  std::optional<Eigen::Vector3d> gps_enu;
  double gps_sigma_m = 0.0;
};
void CheckKeyFrameRecord(const KeyFrameRecordCheck& record, const std::filesystem::path& file);

// A map point's stored state.
void CheckPointRecord(std::uint64_t id, const Eigen::Vector3d& position, int visible, int found,
                      const std::filesystem::path& file);

// The spanning tree: parent ids by keyframe id (kNoParent for a root). Every parent must exist (InputError
// otherwise). A keyframe that is its own ancestor is repaired, not refused: the tree is derived from
// covisibility, any forest serves, and before 2026-11-28 semslam wrote a cycle through the first keyframe of
// every map started after a loss. Each cycle is cut above its oldest keyframe, which becomes a root; returns
// those keyframes' ids.
inline constexpr std::uint64_t kNoParent = UINT64_MAX;
std::vector<std::uint64_t> RepairSpanningTree(std::unordered_map<std::uint64_t, std::uint64_t>& parent_of,
                                              const std::filesystem::path& file);

// Largest coordinate (metres) a map may hold: far beyond any drive, far below where float and Ceres break down.
inline constexpr double kMaxMapCoordinateM = 1e7;

}  // namespace semslam
