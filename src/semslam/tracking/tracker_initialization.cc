// Tracker: monocular (two-view) and stereo initialization of a map.

#include <spdlog/spdlog.h>

#include <algorithm>
#include <unordered_map>

#include "semslam/features/matching.h"
#include "semslam/geometry/two_view.h"
#include "semslam/map/map_matcher.h"
#include "semslam/mapping/local_mapper.h"
#include "semslam/mapping/map_optimization.h"
#include "semslam/tracking/tracker.h"

namespace semslam {

bool Tracker::InitializeStereo(Frame& frame) {
  if (frame.num_features() < 500) return false;
  auto lock = map_.WriteLock();
  frame.SetPose(Rigid3d());
  KeyFrame* kf = map_.AddKeyFrame(frame);
  new_keyframes_.push_back({kf->id(), frame.id()});
  int created = 0;
  for (size_t i = 0; i < frame.num_features(); ++i) {
    const auto world = kf->UnprojectStereo(static_cast<int>(i));
    if (!world) continue;
    MapPoint* p = map_.AddMapPoint(*world, kf);
    p->AddObservation(kf, static_cast<int>(i));
    kf->SetMapPoint(static_cast<int>(i), p);
    p->UpdateDescriptor();
    p->UpdateNormalAndDepth();
    frame.map_points[i] = p;
    ++created;
  }
  spdlog::info("stereo map initialized with {} points", created);
  last_keyframe_ = reference_keyframe_ = kf;
  frame.reference_keyframe = kf;
  local_keyframes_ = {kf};
  local_points_ = {frame.map_points.begin(), frame.map_points.end()};
  std::erase(local_points_, nullptr);
  if (mapper_) keyframes_for_mapper_.push_back(kf);
  return true;
}

bool Tracker::InitializeMonocular(Frame& frame) {
  if (!init_frame_) {
    if (frame.num_features() > 100) {
      init_frame_ = std::make_unique<Frame>(frame);
      init_prior_positions_.clear();
      for (const auto& kp : frame.features().keypoints) init_prior_positions_.push_back(kp.pixel);
      init_between_frames_.clear();
    }
    return false;
  }
  if (frame.num_features() <= 100) {
    init_frame_.reset();
    return false;
  }
  InitializationMatchOptions init_matching;
  init_matching.max_level = options_.init_match_max_level;
  init_matching.max_level_difference = options_.init_match_level_difference;
  std::vector<int> matches12 = MatchForInitialization(init_frame_->features(), frame.features(),
                                                      init_prior_positions_, 100, init_matching);
  const int num_matches =
      static_cast<int>(std::count_if(matches12.begin(), matches12.end(), [](int m) { return m >= 0; }));
  if (num_matches < options_.init_min_matches) {
    init_frame_.reset();
    return false;
  }
  // The next frame searches around where each feature was seen last, so the windows follow the motion.
  for (size_t i = 0; i < matches12.size(); ++i) {
    if (matches12[i] >= 0)
      init_prior_positions_[i] = frame.features().keypoints[static_cast<size_t>(matches12[i])].pixel;
  }

  std::vector<Eigen::Vector2d> pixels1, pixels2;
  std::vector<int> index1;
  for (size_t i = 0; i < matches12.size(); ++i) {
    if (matches12[i] < 0) continue;
    pixels1.push_back(init_frame_->features().keypoints[i].pixel.cast<double>());
    pixels2.push_back(frame.features().keypoints[static_cast<size_t>(matches12[i])].pixel.cast<double>());
    index1.push_back(static_cast<int>(i));
  }
  TwoViewOptions two_view_options;
  two_view_options.seed = frame.id();
  two_view_options.min_parallax_deg = options_.init_min_parallax_deg;
  two_view_options.parallax_rank = options_.init_parallax_rank;
  two_view_options.min_good_points = options_.init_min_points;
  // The keypoints are undistorted already: the frame's own (pinhole) camera, not the lens's.
  const TwoViewResult two_view =
      InitializeTwoView(pixels1, pixels2, init_frame_->data().camera, two_view_options);
  if (!two_view.success) {
    spdlog::debug(
        "frame {}: monocular initialization failed: {} ({}, S_H/(S_H+S_F) {:.2f}, {} inliers, {} and {} good "
        "in the best two motions)",
        frame.id(), two_view.reason, two_view.model.empty() ? "no model" : two_view.model,
        two_view.score_ratio, two_view.num_inliers, two_view.num_good, two_view.second_best_good);
    // Kept to be posed in the map once it starts (a few dozen frames at most: older ones go).
    if (init_between_frames_.size() >= kMaxBetweenFrames) init_between_frames_.pop_front();
    init_between_frames_.push_back(frame);
    return false;
  }

  auto lock = map_.WriteLock();
  init_frame_->SetPose(Rigid3d());
  frame.SetPose(two_view.camera2_from_camera1);
  KeyFrame* kf1 = map_.AddKeyFrame(*init_frame_);
  KeyFrame* kf2 = map_.AddKeyFrame(frame);
  new_keyframes_.push_back({kf1->id(), init_frame_->id()});
  new_keyframes_.push_back({kf2->id(), frame.id()});
  for (size_t m = 0; m < two_view.points.size(); ++m) {
    if (!two_view.triangulated[m]) continue;
    const int i1 = index1[m];
    const int i2 = matches12[static_cast<size_t>(i1)];
    MapPoint* p = map_.AddMapPoint(two_view.points[m], kf2);
    kf1->SetMapPoint(i1, p);
    kf2->SetMapPoint(i2, p);
    p->AddObservation(kf1, i1);
    p->AddObservation(kf2, i2);
    p->UpdateDescriptor();
    p->UpdateNormalAndDepth();
  }
  kf1->UpdateConnections();
  kf2->UpdateConnections();
  const std::uint32_t map_id = kf1->map_id();
  spdlog::info("monocular map {} initialized from frames {} and {} with {} points ({})", map_id,
               init_frame_->id(), frame.id(), kf2->CountTrackedPoints(1), two_view.model);

  // Full bundle adjustment of the two views, then the scale: median scene depth 1.
  GlobalBundleAdjustmentOptions two_view_ba;
  two_view_ba.iterations = 20;
  // Every point just passed the two views' inlier test, and dropping either of its two observations would take
  // the point along: the count of points decides below whether the map starts.
  two_view_ba.drop_outliers = false;
  GlobalBundleAdjustment(map_, map_id, two_view_ba);
  const double median_depth = kf1->SceneDepthQuantile(2);
  if (median_depth <= 0 || kf2->CountTrackedPoints(1) < options_.init_min_points) {
    spdlog::debug("frame {}: initialization rejected after BA (depth {}, {} points)", frame.id(),
                  median_depth, kf2->CountTrackedPoints(1));
    map_.DiscardMap(map_id);
    init_frame_.reset();
    return false;
  }
  const double inv = 1.0 / median_depth;
  Rigid3d pose2 = kf2->camera_from_world();
  pose2.translation *= inv;
  kf2->SetPose(pose2);
  for (MapPoint* p : map_.MapPointsOfMap(map_id)) {
    p->SetPosition(p->position() * inv);
    p->UpdateNormalAndDepth();
  }
  frame.SetPose(kf2->camera_from_world());
  frame.map_points = kf2->map_points();
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);
  frame.reference_keyframe = kf2;
  last_keyframe_ = reference_keyframe_ = kf2;
  // The motion between the two frames, per frame, predicts the next one: matched to the second keyframe
  // without a prediction instead, a street of repeated facades pulled the third frame 1.8 degrees off, and
  // the motion model carried that turn on (9 degrees by the fifteenth frame, then lost).
  const double steps = static_cast<double>(std::max<std::uint64_t>(frame.id() - init_frame_->id(), 1));
  velocity_ = Interpolate(Rigid3d(), kf2->camera_from_world() * kf1->world_from_camera(), 1.0 / steps);
  last_big_change_ = map_.big_change_index();  // the new map is what the next frame is tracked in
  local_keyframes_ = {kf1, kf2};
  local_points_ = map_.MapPointsOfMap(map_id);
  // The frames from the map's first one to this one get poses in it, so the trajectory starts where the map
  // does.
  PoseInitializationFrames(kf1, kf2);
  inliers_ = kf2->CountTrackedPoints(1);
  lock.unlock();
  init_frame_.reset();
  init_between_frames_.clear();
  if (mapper_) keyframes_for_mapper_.insert(keyframes_for_mapper_.end(), {kf1, kf2});
  return true;
}

void Tracker::PoseInitializationFrames(KeyFrame* first, KeyFrame* second) {
  // Each frame between the two starts from the pose interpolated between them (the first keyframe is the
  // map's origin), then is tracked against the second keyframe's points; without enough matches it keeps
  // the interpolated pose.
  const Rigid3d second_from_first = second->camera_from_world() * first->world_from_camera();
  const double t0 = first->timestamp(), t1 = second->timestamp();
  auto interpolated = [&](double timestamp) {
    const double s = t1 > t0 ? std::clamp((timestamp - t0) / (t1 - t0), 0.0, 1.0) : 0.0;
    return Interpolate(Rigid3d(), second_from_first, s);
  };
  std::unordered_map<std::uint64_t, Rigid3d> tracked;
  for (Frame& frame : init_between_frames_) {
    if (frame.id() <= first->frame_id() || frame.id() >= second->frame_id()) continue;
    frame.SetPose(interpolated(frame.timestamp()));
    std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
    std::fill(frame.outliers.begin(), frame.outliers.end(), false);
    if (SearchFromKeyFrame(frame, *second, {}, 15.0f, MatcherThresholds::kHigh) < 30) continue;
    if (OptimizeFramePose(frame) >= 30) tracked[frame.id()] = frame.camera_from_world();
  }
  for (FrameRecord& record : records_) {
    if (record.frame_id < first->frame_id() || record.frame_id >= second->frame_id()) continue;
    const auto it = tracked.find(record.frame_id);
    record.reference = first;
    record.camera_from_reference = it != tracked.end() ? it->second : interpolated(record.timestamp);
    record.reference_scale = first->scale_correction();
    record.source = (record.frame_id == first->frame_id() || it != tracked.end()) ? PoseProvenance::kTracked
                                                                                  : PoseProvenance::kInterpolated;
  }
}

}  // namespace semslam
