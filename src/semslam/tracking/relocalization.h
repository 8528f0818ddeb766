#pragma once
// Relocalization of a frame against the keyframes of the map: points searched where a predicted pose
// projects them, or bag-of-words candidates grouped by covisibility and BoW matching; then PnP RANSAC, pose
// refinement and a guided search for more matches.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "semslam/geometry/rigid3.h"
#include "semslam/map/frame.h"
#include "semslam/map/map.h"

namespace semslam {

class KeyFrameDatabase;

// Where a camera lost a moment ago can be: within `radius` of where the motion before the loss puts it, and
// not behind where it was last tracked. A car does not reverse in the seconds of a loss, while a street of
// repeating fronts offers a look-alike place a block back (seed 2027: 19 m back, an ATE of 4 m).
struct MotionSinceLoss {
  Eigen::Vector3d last_center = Eigen::Vector3d::Zero();       // at the last tracked frame
  Eigen::Vector3d predicted_center = Eigen::Vector3d::Zero();  // the motion model's prediction for now
  double radius = 0.0;
  // How far behind last_center, along the predicted motion, a pose may be: its noise. Going back is not
  // checked when the predicted motion is shorter than this (a car standing still).
  double backward_tolerance = 0.0;

  // Empty when a camera at `center` fits the motion; else the reason it does not.
  std::optional<std::string> Refuses(const Eigen::Vector3d& center) const;
};

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
  // False: only the search around `predicted`. Lost for long, the camera may be far from the prediction,
  // where a look-alike place (a street of repeating fronts, a block back) matches as well as the true one:
  // a place recognized by appearance alone is then left to the map merge, which checks it against several
  // keyframes of both maps.
  bool by_appearance = true;
};

// Tries the nearby keyframes' points where the prediction projects them, then (options.by_appearance) the
// nearby keyframes and the place candidates (map/place_candidates.h) of `frame` (whose bag of words is
// computed) by bag of words, until one gives a pose that `options.plausible` accepts with at least 50
// inliers (30 when found where the prediction put it). `optimize_pose` refines the frame pose from
// frame.map_points and sets frame.outliers, returning the inlier count. On success the frame has its pose and
// matches. Read lock.
bool RelocalizeFrame(Frame& frame, const KeyFrameDatabase& database, const Map& map,
                     const std::function<int(Frame&)>& optimize_pose,
                     const RelocalizationOptions& options = {});

}  // namespace semslam
