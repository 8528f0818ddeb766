#pragma once
// Where each drive of a merge's atlas (system/session_merge.h) is: every session's keyframes as its input map
// held them, and its frames carried through every move the merge makes (each frame follows the keyframe
// nearest in frame index, as in a run).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <vector>

#include "semslam/geo/frame_position.h"
#include "semslam/geometry/rigid3.h"
#include "semslam/map/keyframe.h"
#include "semslam/system/merge_inputs.h"

namespace semslam {

// A keyframe of one session in one map as the input held it.
struct Anchor {
  KeyFrame* keyframe = nullptr;
  Rigid3d world_from_keyframe;  // as loaded
  double scale_correction = 1.0;
};
using AnchorsByFrame = std::map<std::uint64_t, Anchor>;  // by frame index

// What one session of the atlas is, and where its frames are.
struct SessionRecord {
  std::uint32_t id = 0;
  std::filesystem::path run;
  std::uint32_t first_map_id = 0;  // where its input's map ids went in the atlas
  std::optional<InputSession> input;
  std::map<std::uint32_t, AnchorsByFrame> anchors;  // by the map id the keyframes had when loaded
  std::vector<FramePose> frames;                    // moved, after the merge
};

// A session's good keyframes where the atlas holds them now, in frame order.
std::vector<FramePose> SessionKeyFrames(const SessionRecord& s);

// How a frame's offset from its keyframe is scaled when the keyframe moves.
enum class FrameScale {
  kKeyFrame,          // by the scale the keyframe carries (stereo: none)
  kNeighbourSpacing,  // by the stretch of the keyframe's spacing to its drive's nearest keyframes (monocular)
};

// A session's frames where the atlas holds them now (its keyframes otherwise), and how many have no keyframe
// of theirs left.
std::vector<FramePose> SessionFrames(const SessionRecord& s, FrameScale frame_scale, size_t* unanchored);

}  // namespace semslam
