#pragma once
// Moving a map of the atlas into a metric world frame (ENU) where GPS fusion placed its keyframes, so that
// the map itself, not only a transform beside it, is in the world: its points and keyframes in metres, its
// frames following their keyframes, and every map placed this way in one frame with the others.

#include <cstdint>
#include <unordered_map>

#include "semslam/geometry/sim3.h"
#include "semslam/map/map.h"

namespace semslam {

// Each keyframe of `map_id` found in `world_from_keyframe` (by id) takes that pose: its rotation and centre,
// and its scale (world units per map unit there) stretches the map around it (KeyFrame::CorrectScale, which
// the frames kept relative to it follow). Each point follows its reference keyframe, or the nearest good
// ancestor of a culled one. Keyframes left out (of another session, or made since the poses were found)
// follow their nearest ancestor given a pose, or, when none is, `world_from_map` (the map's best single
// similarity into the world). Returns how many keyframes took a pose of their own. Write lock.
int MoveMapIntoWorld(Map& map, std::uint32_t map_id,
                     const std::unordered_map<std::uint64_t, Sim3d>& world_from_keyframe,
                     const Sim3d& world_from_map);

}  // namespace semslam
