#include "semslam/system/merge_session_frames.h"

#include <algorithm>

#include "semslam/geometry/sim3.h"
#include "semslam/system/atlas_outputs.h"

namespace semslam {

namespace {

// A frame's pose now: moved with its anchor keyframe (rigidly, and scaled by the keyframe's scale change).
std::optional<FramePose> FollowAnchor(const AnchorsByFrame& anchors, const FramePose& frame) {
  const Anchor* best = nullptr;
  std::uint64_t best_gap = UINT64_MAX;
  for (auto it = anchors.lower_bound(frame.frame_index);; --it) {
    if (it != anchors.end() && !it->second.keyframe->is_bad()) {
      const std::uint64_t gap =
          it->first > frame.frame_index ? it->first - frame.frame_index : frame.frame_index - it->first;
      if (gap < best_gap) {
        best_gap = gap;
        best = &it->second;
      }
      if (it->first <= frame.frame_index) break;
    }
    if (it == anchors.begin()) break;
  }
  if (best == nullptr) return std::nullopt;
  const KeyFrame& kf = *best->keyframe;
  const double scale = kf.scale_correction() / best->scale_correction;
  const Sim3d now_from_loaded = Sim3d(kf.world_from_camera()) *
                                Sim3d(scale, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero()) *
                                Sim3d(best->world_from_keyframe).Inverse();
  FramePose moved = frame;
  moved.world_from_camera = now_from_loaded.TransformPose(frame.world_from_camera);
  moved.map_id = kf.map_id();
  return moved;
}

}  // namespace

std::vector<FramePose> SessionKeyFrames(const SessionRecord& s) {
  std::vector<FramePose> keyframes;
  for (const auto& [loaded_map, anchors] : s.anchors) {
    for (const auto& [frame, anchor] : anchors) {
      if (anchor.keyframe->is_bad()) continue;
      keyframes.push_back({frame, static_cast<long long>(anchor.keyframe->id()), anchor.keyframe->timestamp(),
                           anchor.keyframe->world_from_camera(), anchor.keyframe->map_id(), false});
    }
  }
  std::sort(keyframes.begin(), keyframes.end(),
            [](const FramePose& a, const FramePose& b) { return a.frame_index < b.frame_index; });
  return keyframes;
}

std::vector<FramePose> SessionFrames(const SessionRecord& s, size_t* unanchored) {
  if (!s.input) return SessionKeyFrames(s);
  std::vector<FramePose> frames;
  for (const FramePose& f : ReadFramesCsv(s.input->frames_csv)) {
    const auto anchors = s.anchors.find(f.map_id + s.first_map_id);
    const std::optional<FramePose> moved =
        anchors != s.anchors.end() ? FollowAnchor(anchors->second, f) : std::nullopt;
    if (moved) {
      frames.push_back(*moved);
    } else if (unanchored != nullptr) {
      ++*unanchored;
    }
  }
  return frames;
}

}  // namespace semslam
