// Tracker: a frame tracked from the last one: the constant-velocity prediction, and the reference keyframe
// by bag of words.

#include <spdlog/spdlog.h>

#include <algorithm>
#include <utility>
#include <vector>

#include "semslam/map/map_matcher.h"
#include "semslam/tracking/tracker.h"

namespace semslam {

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

int Tracker::TrackWithMotionModel(Frame& frame) {
  frame.SetPose(*velocity_ * last_frame_->camera_from_world());
  std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
  const float radius = options_.monocular ? 15.0f : 7.0f;
  int n = SearchFromLastFrame(frame, *last_frame_, radius, options_.monocular);
  n = DropDynamicMatches(frame);
  if (n < 20) {
    std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
    SearchFromLastFrame(frame, *last_frame_, 2.0f * radius, options_.monocular);
    n = DropDynamicMatches(frame);
  }
  if (n < 20) return 0;
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);
  OptimizeFramePose(frame);
  const int inliers = DiscardOutliers(frame);
  return inliers >= 10 ? inliers : 0;
}

bool Tracker::TrackWithMotionModelOrReference(Frame& frame) {
  const int predicted = TrackWithMotionModel(frame);
  if (predicted == 0) return TrackReferenceKeyFrame(frame) > 0;
  const int last_points = last_frame_->CountMatches();
  if (predicted >= options_.motion_model_min_kept_ratio * last_points) return true;
  const Rigid3d predicted_pose = frame.camera_from_world();
  std::vector<MapPoint*> predicted_points = frame.map_points;
  const int unpredicted = TrackReferenceKeyFrame(frame);
  if (unpredicted > predicted) {
    spdlog::info(
        "frame {}: the motion model kept {} of the last frame's {} points; matched to the reference "
        "keyframe without prediction: {} inliers, that pose is kept",
        frame.id(), predicted, last_points, unpredicted);
    return true;
  }
  // Both searches leave no outlier flags (DiscardOutliers clears them), so the motion model's matches go back
  // as they were.
  frame.SetPose(predicted_pose);
  frame.map_points = std::move(predicted_points);
  return true;
}

}  // namespace semslam
