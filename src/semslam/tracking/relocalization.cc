#include "semslam/tracking/relocalization.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "semslam/geometry/pnp.h"
#include "semslam/map/map_matcher.h"
#include "semslam/map/place_candidates.h"
#include "semslam/place/keyframe_database.h"

namespace semslam {

namespace {

constexpr int kMinInliers = 50;
// Near the motion model's prediction fewer do (right after a gap a monocular map holds few points the camera
// still sees); the pose must also be where the prediction allows (options.plausible) and the tracker's local
// map must confirm it (Tracker::TrackLocalMap).
constexpr int kMinInliersNearPrediction = 30;

// Clears the matches pose optimization rejected.
void DropOutliers(Frame& frame) {
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    if (frame.outliers[i]) {
      frame.map_points[i] = nullptr;
      frame.outliers[i] = false;
    }
  }
}

// A pose for `frame` from its matches to map points (`matches`, one slot per keypoint): PnP RANSAC, pose
// refinement, then a guided search in the points of `keyframes` (the first is the frame's reference) for more
// matches. Accepted with min_inliers inliers that options.plausible accepts; the frame then has its pose and
// matches.
bool PoseFromMatches(Frame& frame, const std::vector<MapPoint*>& matches,
                     const std::vector<KeyFrame*>& keyframes, int min_inliers,
                     const std::function<int(Frame&)>& optimize_pose, const RelocalizationOptions& options) {
  KeyFrame& keyframe = *keyframes.front();
  const auto& camera = frame.data().camera;
  Points3d world_points, bearings;
  std::vector<size_t> slots;
  for (size_t i = 0; i < matches.size(); ++i) {
    if (matches[i] == nullptr || matches[i]->is_bad() || (options.exclude_dynamic && matches[i]->IsDynamic()))
      continue;
    world_points.push_back(matches[i]->position());
    bearings.push_back(camera.Unproject(frame.features().keypoints[i].pixel.cast<double>()));
    slots.push_back(i);
  }
  PnpRansacOptions pnp_options;
  pnp_options.max_reprojection_error_px = 2.0 * std::sqrt(5.991);
  pnp_options.focal_length = camera.fx;
  pnp_options.seed = frame.id() ^ keyframe.id();
  const auto pnp = SolvePnpRansac(world_points, bearings, pnp_options);
  if (!pnp || pnp->num_inliers < 10) return false;

  frame.SetPose(pnp->camera_from_world);
  std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);
  for (size_t k = 0; k < slots.size(); ++k) {
    if (pnp->inliers[k]) frame.map_points[slots[k]] = matches[slots[k]];
  }
  int good = optimize_pose(frame);
  if (good < 10) return false;
  DropOutliers(frame);
  auto found = [&frame] {
    std::set<MapPoint*> points;
    for (MapPoint* p : frame.map_points) {
      if (p != nullptr) points.insert(p);
    }
    return points;
  };
  auto search = [&](float radius, int max_distance) {
    int more = 0;
    for (KeyFrame* kf : keyframes) more += SearchFromKeyFrame(frame, *kf, found(), radius, max_distance);
    return more;
  };
  if (good < min_inliers) {
    // A guided search in the keyframes' map points for more matches, then again with a tighter window.
    const int more = search(10.0f, 100);
    if (good + more >= min_inliers) {
      good = optimize_pose(frame);
      if (good > 30 && good < min_inliers) {
        DropOutliers(frame);
        const int extra = search(3.0f, 64);
        if (good + extra >= min_inliers) good = optimize_pose(frame);
      }
      DropOutliers(frame);
    }
  }
  if (good < min_inliers || (options.plausible && !options.plausible(frame))) return false;
  frame.reference_keyframe = &keyframe;
  return true;
}

// The nearby keyframes' points, searched where the predicted pose projects them (a wide window: the
// prediction of a lost moment is off by metres along the road); then PnP on those matches.
bool RelocalizeFromPrediction(Frame& frame, const std::vector<KeyFrame*>& nearby, const Rigid3d& predicted,
                              const std::function<int(Frame&)>& optimize_pose,
                              const RelocalizationOptions& options) {
  constexpr float kRadiusPx = 40.0f;  // at the finest level
  constexpr int kMinMatches = 20;
  frame.SetPose(predicted);
  std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);
  std::set<MapPoint*> found;
  KeyFrame* best = nullptr;
  int best_matches = 0;
  for (KeyFrame* kf : nearby) {
    const int matches = SearchFromKeyFrame(frame, *kf, found, kRadiusPx, 100);
    if (matches > best_matches) {
      best_matches = matches;
      best = kf;
    }
    for (MapPoint* p : frame.map_points) {
      if (p != nullptr) found.insert(p);
    }
  }
  if (best == nullptr || static_cast<int>(found.size()) < kMinMatches) return false;
  const std::vector<MapPoint*> matches = frame.map_points;
  std::vector<KeyFrame*> keyframes = {best};
  for (KeyFrame* kf : nearby) {
    if (kf != best) keyframes.push_back(kf);
  }
  return PoseFromMatches(frame, matches, keyframes, kMinInliersNearPrediction, optimize_pose, options);
}

}  // namespace

std::optional<std::string> MotionSinceLoss::Refuses(const Eigen::Vector3d& center) const {
  const double off = (center - predicted_center).norm();
  if (off > radius) return fmt::format("{:.2f} from where the camera can be (limit {:.2f})", off, radius);
  const Eigen::Vector3d ahead = predicted_center - last_center;
  if (ahead.norm() <= backward_tolerance) return std::nullopt;
  const double along = (center - last_center).dot(ahead.normalized());
  if (along < -backward_tolerance) {
    return fmt::format(
        "{:.2f} behind where the camera was last tracked (limit {:.2f}), against {:.2f} ahead "
        "by the motion model",
        -along, backward_tolerance, ahead.norm());
  }
  return std::nullopt;
}

bool RelocalizeFrame(Frame& frame, const KeyFrameDatabase& database, const Map& map,
                     const std::function<int(Frame&)>& optimize_pose, const RelocalizationOptions& options) {
  std::vector<KeyFrame*> nearby;
  std::set<const KeyFrame*> tried;
  for (KeyFrame* kf : options.nearby) {
    if (kf != nullptr && !kf->is_bad() && (!options.map_id || kf->map_id() == *options.map_id) &&
        tried.insert(kf).second) {
      nearby.push_back(kf);
    }
  }
  if (options.predicted && !nearby.empty() &&
      RelocalizeFromPrediction(frame, nearby, *options.predicted, optimize_pose, options)) {
    return true;
  }
  if (!options.by_appearance) return false;
  PlaceCandidateOptions candidate_options;
  candidate_options.map_id = options.map_id;
  std::vector<KeyFrame*> candidates = nearby;
  for (KeyFrame* kf : FindPlaceCandidates(frame.bow, database, map, candidate_options)) {
    if (tried.insert(kf).second) candidates.push_back(kf);
  }
  for (KeyFrame* kf : candidates) {
    std::vector<MapPoint*> matches;
    if (SearchByBow(*kf, frame, matches, 0.75f) < 15) continue;
    if (PoseFromMatches(frame, matches, {kf}, kMinInliers, optimize_pose, options)) return true;
  }
  return false;
}

}  // namespace semslam
