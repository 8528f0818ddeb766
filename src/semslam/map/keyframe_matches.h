#pragma once
// Matches between two keyframes' map points, each in its own keyframe's camera frame: what a loop's or a
// merge's Sim(3) is estimated, refined and checked on.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "semslam/map/keyframe.h"
#include "semslam/map/map_point.h"

namespace semslam {

struct KeyFramePointMatch {
  size_t slot1 = 0;  // keypoint of keyframe 1 that holds point 1
  size_t slot2 = 0;  // keypoint of keyframe 2 that observes the matched point
  Eigen::Vector3d point1 = Eigen::Vector3d::Zero();  // keyframe 1's map point, in camera 1's frame
  Eigen::Vector3d point2 = Eigen::Vector3d::Zero();  // its match, a map point of keyframe 2, in camera 2's frame
};

// The usable matches of `matches12` (one slot per keypoint of kf1: a map point of kf2, or null): kf1 holds a
// point in that slot, neither point is bad, and kf2 observes the match. Read lock on the map held by the caller.
std::vector<KeyFramePointMatch> MatchesInCameraFrames(const KeyFrame& kf1, const KeyFrame& kf2,
                                                      const std::vector<MapPoint*>& matches12);

}  // namespace semslam
