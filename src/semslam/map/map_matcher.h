#pragma once
// Descriptor matching between frames, keyframes and map points, guided by projection, by the
// bag-of-words vocabulary tree, or by epipolar geometry. Call with the map's read lock held (the
// Fuse functions need the write lock).

#include <set>
#include <utility>
#include <vector>

#include "semslam/features/matching.h"
#include "semslam/geometry/sim3.h"
#include "semslam/map/frame.h"
#include "semslam/map/keyframe.h"
#include "semslam/map/map_point.h"

namespace semslam {

// Local-map tracking: matches points whose projection was prepared in their track_* scratch fields.
// `radius_factor` widens the search (e.g. right after relocalization). Returns new matches.
int SearchLocalPoints(Frame& frame, const std::vector<MapPoint*>& points, float radius_factor,
                      float nn_ratio = 0.8f);

// Motion-model tracking: projects the last frame's matched points into `current` (which has a predicted
// pose). `radius` in pixels at level 0. Returns matches.
int SearchFromLastFrame(Frame& current, const Frame& last, float radius, bool monocular);

// Relocalization: projects the points of `keyframe` not in `already_found` into `frame` (with a pose).
int SearchFromKeyFrame(Frame& frame, const KeyFrame& keyframe, const std::set<MapPoint*>& already_found,
                       float radius, int max_distance);

// Bag-of-words matching of a keyframe's map points to a frame's keypoints; `matches` gets one slot per
// frame keypoint. Needs both bag-of-words feature vectors.
int SearchByBow(const KeyFrame& keyframe, const Frame& frame, std::vector<MapPoint*>& matches, float nn_ratio,
                bool check_orientation = true);
// Between two keyframes' map points (loop closing); `matches12` has one slot per keypoint of kf1.
int SearchByBow(const KeyFrame& kf1, const KeyFrame& kf2, std::vector<MapPoint*>& matches12, float nn_ratio);

// Pairs of unmatched keypoints (kf1 index, kf2 index) satisfying the epipolar constraint of F21
// (x2^T F21 x1 = 0), for triangulation of new points.
std::vector<std::pair<int, int>> SearchForTriangulation(const KeyFrame& kf1, const KeyFrame& kf2,
                                                        const Eigen::Matrix3d& f21, bool only_stereo);

// Projects `points` into `keyframe` and merges each with the keyframe's matching keypoint: a keypoint with
// no point gets the observation; one with another point keeps the better-observed of the two. Write lock.
int Fuse(KeyFrame* keyframe, const std::vector<MapPoint*>& points, float radius = 3.0f);
// Loop fusion: projects with the corrected similarity `camera_from_world`; where the keypoint already has a
// point, `replace[i]` gets it (the caller replaces it by points[i] under the lock). Read lock suffices.
int FuseWithSim3(const KeyFrame& keyframe, const Sim3d& camera_from_world,
                 const std::vector<MapPoint*>& points, float radius, std::vector<MapPoint*>& replace);

// Loop closing: projects `points` into `keyframe` with a similarity pose and adds matches to `matched`
// (one slot per keyframe keypoint, existing entries kept).
int SearchBySim3Projection(const KeyFrame& keyframe, const Sim3d& camera_from_world,
                           const std::vector<MapPoint*>& points, std::vector<MapPoint*>& matched, int radius);
// Guided matching of the map points of two keyframes given kf1_from_kf2 (both directions must agree).
int SearchBySim3(const KeyFrame& kf1, const KeyFrame& kf2, std::vector<MapPoint*>& matches12,
                 const Sim3d& kf1_from_kf2, float radius);

}  // namespace semslam
