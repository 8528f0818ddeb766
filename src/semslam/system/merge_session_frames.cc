#include "semslam/system/merge_session_frames.h"

#include <algorithm>
#include <iterator>

#include "semslam/geometry/sim3.h"
#include "semslam/system/atlas_outputs.h"

namespace semslam {

namespace {

constexpr int kScaleNeighbours = 3;  // keyframes on each side of the anchor whose spacing gives its stretch

// How much the map around an anchor keyframe was stretched since it was loaded: its spacing to the nearest
// keyframes of its drive and map, now against then. Keyframes hold their positions to a fraction of a per
// cent of their spacing, where the scale a keyframe carries through merges, loops and adjustments
// (KeyFrame::scale_correction) drifts by per cents at a drive's ends, and the frames after a drive's last
// keyframe would carry that over tens of metres.
std::optional<double> NeighbourStretch(const AnchorsByFrame& anchors, AnchorsByFrame::const_iterator at) {
  const Eigen::Vector3d now = at->second.keyframe->world_from_camera().translation;
  const Eigen::Vector3d then = at->second.world_from_keyframe.translation;
  double spacing_now = 0.0, spacing_then = 0.0;
  const auto add = [&](const Anchor& a) {
    if (a.keyframe->is_bad() || a.keyframe->map_id() != at->second.keyframe->map_id()) return false;
    spacing_now += (a.keyframe->world_from_camera().translation - now).norm();
    spacing_then += (a.world_from_keyframe.translation - then).norm();
    return true;
  };
  int found = 0;
  for (auto it = std::next(at); it != anchors.end() && found < kScaleNeighbours; ++it)
    found += add(it->second);
  found = 0;
  for (auto it = at; it != anchors.begin() && found < kScaleNeighbours;) found += add((--it)->second);
  if (!(spacing_then > 0.0) || !(spacing_now > 0.0)) return std::nullopt;
  return spacing_now / spacing_then;
}

// A frame's pose now: moved with its anchor keyframe (rigidly, and scaled as the map around the keyframe).
std::optional<FramePose> FollowAnchor(const AnchorsByFrame& anchors, const FramePose& frame,
                                      FrameScale frame_scale) {
  AnchorsByFrame::const_iterator best = anchors.end();
  std::uint64_t best_gap = UINT64_MAX;
  for (auto it = anchors.lower_bound(frame.frame_index);; --it) {
    if (it != anchors.end() && !it->second.keyframe->is_bad()) {
      const std::uint64_t gap =
          it->first > frame.frame_index ? it->first - frame.frame_index : frame.frame_index - it->first;
      if (gap < best_gap) {
        best_gap = gap;
        best = it;
      }
      if (it->first <= frame.frame_index) break;
    }
    if (it == anchors.begin()) break;
  }
  if (best == anchors.end()) return std::nullopt;
  const Anchor& anchor = best->second;
  const KeyFrame& kf = *anchor.keyframe;
  double scale = kf.scale_correction() / anchor.scale_correction;
  if (frame_scale == FrameScale::kNeighbourSpacing) {
    if (const std::optional<double> stretch = NeighbourStretch(anchors, best)) scale = *stretch;
  }
  const Sim3d now_from_loaded = Sim3d(kf.world_from_camera()) *
                                Sim3d(scale, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero()) *
                                Sim3d(anchor.world_from_keyframe).Inverse();
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

std::vector<FramePose> SessionFrames(const SessionRecord& s, FrameScale frame_scale, size_t* unanchored) {
  if (!s.input) return SessionKeyFrames(s);
  std::vector<FramePose> frames;
  for (const FramePose& f : ReadFramesCsv(s.input->frames_csv)) {
    const auto anchors = s.anchors.find(f.map_id + s.first_map_id);
    const std::optional<FramePose> moved =
        anchors != s.anchors.end() ? FollowAnchor(anchors->second, f, frame_scale) : std::nullopt;
    if (moved) {
      frames.push_back(*moved);
    } else if (unanchored != nullptr) {
      ++*unanchored;
    }
  }
  return frames;
}

}  // namespace semslam
