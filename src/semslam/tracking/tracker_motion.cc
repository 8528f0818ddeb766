// Tracker: a frame tracked from the last one: the constant-velocity prediction, predictions turned around
// it, and the reference keyframe by bag of words.

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <utility>
#include <vector>

#include "semslam/map/map_matcher.h"
#include "semslam/tracking/tracker.h"

namespace semslam {

namespace {

// Search radius around a projected point, in pixels at level 0, from the constant-velocity prediction.
float MotionModelRadius(bool monocular) { return monocular ? 15.0f : 7.0f; }

// A turned prediction replaces the motion model's only when it tracks half as many points again: one about
// as good is the same pose found from another start, and frames the prediction tracks stay as they were.
constexpr double kTurnedGain = 1.5;

}  // namespace

int Tracker::TrackReferenceKeyFrame(Frame& frame) {
  ComputeBow(frame);
  std::vector<MapPoint*> matches;
  SearchByBow(*reference_keyframe_, frame, matches, 0.7f);
  frame.map_points = matches;
  if (DropDynamicMatches(frame) < 15) return 0;
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);
  frame.SetPose(last_frame_->camera_from_world());
  OptimizeFramePose(frame);
  const int inliers = DiscardOutliers(frame);
  return inliers >= 10 ? inliers : 0;
}

int Tracker::TrackFromPrediction(Frame& frame, const Rigid3d& camera_from_world, int more_than) {
  frame.SetPose(camera_from_world);
  std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
  const float radius = MotionModelRadius(options_.monocular);
  SearchFromLastFrame(frame, *last_frame_, radius, options_.monocular);
  int n = DropDynamicMatches(frame);
  if (n < 20) {
    std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
    SearchFromLastFrame(frame, *last_frame_, 2.0f * radius, options_.monocular);
    n = DropDynamicMatches(frame);
  }
  // A pose keeps at most its matches as inliers: one that cannot pass `more_than` is not optimized.
  if (n < 20 || n <= more_than) return 0;
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);
  OptimizeFramePose(frame);
  const int inliers = DiscardOutliers(frame);
  return inliers >= 10 ? inliers : 0;
}

int Tracker::TrackWithTurnedPredictions(Frame& frame, const Rigid3d& predicted, int more_than) {
  // Turned about the camera's own centre (a rotation applied on the camera side keeps it), in steps of
  // one search window's width, so that together the windows cover two widths either way.
  const double step = 2.0 * MotionModelRadius(options_.monocular) / frame.data().camera.fx;
  std::vector<Rigid3d> starts;
  // No turn since the last frame: the rate of turn or pitch of the last step stopped (the top of a bump).
  const Eigen::Quaterniond& last_rotation = last_frame_->camera_from_world().rotation;
  starts.emplace_back(last_rotation,
                      last_rotation * (predicted.rotation.conjugate() * predicted.translation));
  // Pitch (about x) and heading (about y), one and two steps either way.
  const std::array<Eigen::Vector3d, 2> axes{Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()};
  for (const Eigen::Vector3d& axis : axes) {
    for (const double steps : {-2.0, -1.0, 1.0, 2.0}) {
      starts.push_back(
          Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(steps * step, axis)), Eigen::Vector3d::Zero()) *
          predicted);
    }
  }
  int best = 0;
  Rigid3d best_pose;
  std::vector<MapPoint*> best_points;
  for (const Rigid3d& start : starts) {
    const int inliers = TrackFromPrediction(frame, start, std::max(more_than, best));
    if (inliers > best && inliers > more_than) {
      best = inliers;
      best_pose = frame.camera_from_world();
      best_points = frame.map_points;
    }
  }
  if (best > 0) {
    frame.SetPose(best_pose);
    frame.map_points = std::move(best_points);
  }
  return best;
}

bool Tracker::TrackWithMotionModelOrReference(Frame& frame) {
  const Rigid3d predicted = *velocity_ * last_frame_->camera_from_world();
  int tracked = TrackFromPrediction(frame, predicted);
  const int last_points = last_frame_->CountMatches();
  const auto enough = [&](int inliers) {
    return inliers > 0 && inliers >= options_.motion_model_min_kept_ratio * last_points;
  };
  if (enough(tracked)) return true;
  // The pose and matches to go back to where a later search does worse. Both searches leave no outlier flags
  // (DiscardOutliers clears them).
  Rigid3d kept_pose = frame.camera_from_world();
  std::vector<MapPoint*> kept_points = frame.map_points;
  const auto restore = [&] {
    frame.SetPose(kept_pose);
    frame.map_points = kept_points;
  };
  // Few kept: the rate of turn or pitch may have changed since the last frame (a bump, a tightening turn).
  const int turned = TrackWithTurnedPredictions(frame, predicted, static_cast<int>(kTurnedGain * tracked));
  if (turned > 0) {
    spdlog::debug("frame {}: the motion model kept {} of the last frame's {} points, a turned prediction {}",
                  frame.id(), tracked, last_points, turned);
    tracked = turned;
    kept_pose = frame.camera_from_world();
    kept_points = frame.map_points;
  } else {
    restore();
  }
  if (enough(tracked)) return true;
  if (tracked == 0) return TrackReferenceKeyFrame(frame) > 0;
  const int unpredicted = TrackReferenceKeyFrame(frame);
  if (unpredicted > tracked) {
    spdlog::info(
        "frame {}: the motion model kept {} of the last frame's {} points; matched to the reference "
        "keyframe without prediction: {} inliers, that pose is kept",
        frame.id(), tracked, last_points, unpredicted);
    return true;
  }
  restore();
  return true;
}

}  // namespace semslam
