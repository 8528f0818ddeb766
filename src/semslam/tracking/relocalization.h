#pragma once
// Relocalization of a frame against the keyframes of the map: points searched where a predicted pose
// projects them, or bag-of-words candidates grouped by covisibility and BoW matching; then PnP RANSAC, pose
// refinement and a guided search for more matches.

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "semslam/geometry/rigid3.h"
#include "semslam/map/frame.h"
#include "semslam/map/map.h"

namespace semslam {

class KeyFrameDatabase;

struct RelocalizationOptions {
  bool exclude_dynamic = false;         // points labeled as moving classes are not used
  std::optional<std::uint32_t> map_id;  // only keyframes of this map; none: of any map
  // A pose found is kept only when this accepts it (e.g. where a short loss lets the camera be); null: any.
  std::function<bool(const Frame&)> plausible;
  // Keyframes tried before the bag-of-words candidates: around where tracking was lost a moment ago. After a
  // gap the camera sees those places from further on, which the retrieval may rank below others (a keyframe
  // of twice the features shares more words with anything).
  std::vector<KeyFrame*> nearby;
  // Where the motion model puts the camera: the nearby keyframes' points are first searched where it
  // projects them, which matches what bag-of-words matching misses when the scale has changed (a black-out
  // while driving: the same street, seen 20 m further on).
  std::optional<Rigid3d> predicted;
};

// Tries the nearby keyframes' points where the prediction projects them, then the nearby keyframes and the
// place candidates (map/place_candidates.h) of `frame` (whose bag of words is computed) by bag of words,
// until one gives a pose that `options.plausible` accepts with at least 50 inliers (30 when found where the
// prediction put it). `optimize_pose` refines the frame pose from frame.map_points and sets frame.outliers,
// returning the inlier count. On success the frame has its pose and matches. Read lock.
bool RelocalizeFrame(Frame& frame, const KeyFrameDatabase& database, const Map& map,
                     const std::function<int(Frame&)>& optimize_pose,
                     const RelocalizationOptions& options = {});

}  // namespace semslam
