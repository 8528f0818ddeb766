#pragma once
// Relocalization of a frame against the keyframes of the map: bag-of-words candidates grouped by
// covisibility, BoW matching, PnP RANSAC, pose refinement and a guided search for more matches.

#include <functional>
#include <vector>

#include "semslam/map/frame.h"
#include "semslam/map/map.h"

namespace semslam {

class KeyFrameDatabase;

// Keyframes that look like `frame` (whose bag of words is computed): those sharing many words, scored and
// accumulated over their covisibility neighbourhoods; the best keyframe of each strong group. Read lock.
std::vector<KeyFrame*> DetectRelocalizationCandidates(const Frame& frame, const KeyFrameDatabase& database,
                                                      const Map& map);

// Tries the candidates until one gives a pose with at least 50 inliers. `optimize_pose` refines the frame
// pose from frame.map_points and sets frame.outliers, returning the inlier count. On success the frame has
// its pose and matches. Read lock.
// With `exclude_dynamic`, points labeled as moving classes are not used.
bool RelocalizeFrame(Frame& frame, const KeyFrameDatabase& database, const Map& map,
                     const std::function<int(Frame&)>& optimize_pose, bool exclude_dynamic = false);

}  // namespace semslam
