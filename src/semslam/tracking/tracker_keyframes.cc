// Tracker: keyframe decisions and insertion.

#include <algorithm>
#include <limits>

#include "semslam/mapping/local_mapper.h"
#include "semslam/tracking/tracker.h"

namespace semslam {

bool Tracker::SecondsReached(double elapsed, double seconds) {
  // Timestamps are given to a tenth of a millisecond or finer: a gap of whole frame periods (0.3 s at 10 Hz)
  // counts as reached although its floating-point difference may fall just short.
  constexpr double kTimestampTolerance = 1e-4;
  return elapsed >= seconds - kTimestampTolerance;
}

bool Tracker::NeedNewKeyFrame(const Frame& frame) const {
  if (options_.localization_only || mapper_ == nullptr) return false;
  if (mapper_->IsStopped() || mapper_->StopRequested()) return false;
  const size_t num_keyframes = map_.NumKeyFramesOfMap(map_.active_map_id());
  // Right after a relocalization (not a recovery) its pose is not trusted with a keyframe yet, unless the map
  // is so small that it needs keyframes more than it risks a wrong one.
  constexpr size_t kSmallMapKeyFrames = 10;
  if (!SecondsReached(frame.timestamp() - last_relocalization_time_,
                      options_.max_seconds_between_keyframes) &&
      num_keyframes > kSmallMapKeyFrames && !last_relocalization_recovered_) {
    return false;
  }
  const int min_observations = num_keyframes <= 2 ? 2 : 3;
  const int reference_matches = reference_keyframe_->CountTrackedPoints(min_observations);

  int tracked_close = 0, untracked_close = 0;
  if (!options_.monocular) {
    const FrameData& data = frame.data();
    const double close = options_.close_depth_baselines * stereo_->baseline;
    for (size_t i = 0; i < frame.num_features(); ++i) {
      if (data.depth[i] > 0 && data.depth[i] < close) {
        if (frame.map_points[i] != nullptr && !frame.outliers[i]) {
          ++tracked_close;
        } else {
          ++untracked_close;
        }
      }
    }
  }
  const bool need_close = tracked_close < 100 && untracked_close > 70;
  double ratio =
      options_.monocular ? options_.keyframe_tracked_ratio_mono : options_.keyframe_tracked_ratio_stereo;
  if (num_keyframes < 2) ratio = 0.4;

  // When: the longest gap has passed, or the shortest one and tracking thins out, or at once when it
  // collapses (a turn). Never on whether the mapper is idle, so that the keyframes of a drive do not depend
  // on how fast its frames are fed or how busy the machine is (a full queue holds tracking back instead: see
  // SlamSystem::ProcessFrame).
  // A last keyframe from later (another session's, after relocalizing in a loaded map) counts as long ago.
  const double since_last = last_keyframe_ != nullptr && frame.timestamp() >= last_keyframe_->timestamp()
                                ? frame.timestamp() - last_keyframe_->timestamp()
                                : std::numeric_limits<double>::infinity();
  const bool c1a = SecondsReached(since_last, options_.max_seconds_between_keyframes);
  const bool c1b = SecondsReached(since_last, options_.min_seconds_between_keyframes);
  const bool weak = options_.monocular && inliers_ < options_.keyframe_weak_inliers_mono;
  const bool c1c =
      inliers_ < reference_matches * (options_.monocular ? options_.keyframe_collapse_ratio_mono
                                                         : options_.keyframe_collapse_ratio_stereo) ||
      need_close || weak;
  const bool c2 = (inliers_ < reference_matches * ratio || need_close) && inliers_ > 15;
  if (!((c1a || c1b || c1c) && c2)) return false;
  if (!mapper_->AcceptsKeyFrames()) mapper_->InterruptBA();
  return true;
}

void Tracker::CreateNewKeyFrame(Frame& frame) {
  if (!mapper_->SetNotStop(true)) return;  // held until Track() hands the keyframe over
  holding_mapper_ = true;
  auto lock = map_.WriteLock();
  // A merge or loop correction between tracking and now would otherwise put the keyframe where the frame was
  // before the map moved.
  FollowMapChange(frame);
  KeyFrame* kf = map_.AddKeyFrame(frame);
  new_keyframes_.push_back({kf->id(), frame.id()});
  reference_keyframe_ = kf;
  frame.reference_keyframe = kf;
  tracked_camera_from_reference_ = Rigid3d();
  if (!options_.monocular) {
    // Close stereo points the map does not have yet become map points now, so the next frames track them.
    std::vector<std::pair<float, int>> by_depth;
    const FrameData& data = frame.data();
    for (size_t i = 0; i < frame.num_features(); ++i) {
      if (data.depth[i] > 0) by_depth.emplace_back(data.depth[i], static_cast<int>(i));
    }
    std::sort(by_depth.begin(), by_depth.end());
    const double close = options_.close_depth_baselines * stereo_->baseline;
    int count = 0;
    for (const auto& [depth, i] : by_depth) {
      MapPoint* existing = kf->map_point(i);
      const bool create = existing == nullptr || existing->is_bad() || existing->num_observations() < 1;
      if (create) {
        if (existing != nullptr) kf->SetMapPoint(i, nullptr);
        const auto world = kf->UnprojectStereo(i);
        MapPoint* p = map_.AddMapPoint(*world, kf);
        p->AddObservation(kf, i);
        kf->SetMapPoint(i, p);
        p->UpdateDescriptor();
        p->UpdateNormalAndDepth();
        frame.map_points[static_cast<size_t>(i)] = p;
      }
      ++count;
      if (depth > close && count > 100) break;
    }
  }
  last_keyframe_ = kf;
  keyframes_for_mapper_.push_back(kf);
}

}  // namespace semslam
