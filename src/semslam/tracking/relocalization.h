#pragma once
// Relocalization of a frame against the keyframes of the map: bag-of-words candidates grouped by
// covisibility, BoW matching, PnP RANSAC, pose refinement and a guided search for more matches.

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "semslam/map/frame.h"
#include "semslam/map/map.h"

namespace semslam {

class KeyFrameDatabase;

struct RelocalizationOptions {
  bool exclude_dynamic = false;         // points labeled as moving classes are not used
  std::optional<std::uint32_t> map_id;  // only keyframes of this map; none: of any map
  // A pose found is kept only when this accepts it (e.g. where a short loss lets the camera be); null: any.
  std::function<bool(const Frame&)> plausible;
};

// Tries the place candidates (map/place_candidates.h) of `frame` (whose bag of words is computed) until one
// gives a pose with at least 50 inliers that `options.plausible` accepts. `optimize_pose` refines the frame
// pose from frame.map_points and sets frame.outliers, returning the inlier count. On success the frame has
// its pose and matches. Read lock.
bool RelocalizeFrame(Frame& frame, const KeyFrameDatabase& database, const Map& map,
                     const std::function<int(Frame&)>& optimize_pose,
                     const RelocalizationOptions& options = {});

}  // namespace semslam
