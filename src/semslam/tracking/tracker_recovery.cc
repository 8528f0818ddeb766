// Tracker: when tracking is lost: predicted poses, relocalization in the active map, a new map.

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "semslam/tracking/relocalization.h"
#include "semslam/tracking/tracker.h"

namespace semslam {

namespace {

// Steps of a motion that takes `step_seconds` from time `from` to time `to`: by the clock (dropped frames
// leave a gap in time), else `frames`.
double MotionSteps(double from, double to, double step_seconds, int frames) {
  return step_seconds > 0.0 && to > from ? (to - from) / step_seconds : static_cast<double>(frames);
}

// `pose` moved on by `steps` (rounded) steps of `velocity`, at most `max_steps`.
Rigid3d CarryMotion(const Rigid3d& velocity, double steps, int max_steps, Rigid3d pose) {
  for (long k = 0; k < std::min<long>(std::lround(steps), max_steps); ++k) pose = velocity * pose;
  return pose;
}

}  // namespace

void Tracker::StartNewMap(Frame& frame, TrackingResult& result) {
  std::uint32_t old_map = 0, new_map = 0;
  {
    auto lock = map_.WriteLock();
    old_map = map_.active_map_id();
    new_map = map_.StartNewMap();
  }
  if (last_tracked_.reference != nullptr) {
    lost_map_ = LostMap{last_tracked_, last_velocity_, last_step_seconds_,
                        records_.size() - 1 - static_cast<size_t>(frames_since_tracked_)};
  }
  spdlog::warn(
      "frame {}: lost for {:.1f} s without relocalizing; map {} is kept and map {} starts (until it "
      "does, map {} is searched first)",
      frame.id(), frame.timestamp() - lost_since_.value_or(frame.timestamp()), old_map, new_map, old_map);
  result.new_map = true;
  ForgetTrackingState();
  if (!options_.monocular && InitializeMap(frame)) {
    state_ = TrackingState::kOk;
    result.initialized_now = true;
  }
}

bool Tracker::InitializeMap(Frame& frame) {
  const bool ok = options_.monocular ? InitializeMonocular(frame) : InitializeStereo(frame);
  if (ok && lost_map_) {
    ++num_new_maps_;
    LinkNewMapToLostMap(frame);
  }
  return ok;
}

void Tracker::LinkNewMapToLostMap(const Frame& frame) {
  auto lock = map_.WriteLock();
  KeyFrame* after = new_keyframes_.empty() ? nullptr : map_.KeyFrameById(new_keyframes_.front().keyframe_id);
  const FrameRecord& last = lost_map_->last_tracked;
  const KeyFrame* before = CurrentReference(last);
  spdlog::info("frame {}: map {} started; map {} is kept, to be merged when its places are seen again",
               frame.id(), map_.active_map_id(),
               before != nullptr ? before->map_id() : last.reference->map_id());
  if (after == nullptr || before == nullptr || !lost_map_->velocity || !(lost_map_->step_seconds > 0.0))
    return;
  // Where the motion before the loss puts the new map's first keyframe, relative to the last keyframe
  // tracked.
  const double seconds = after->timestamp() - last.timestamp;
  const Rigid3d after_from_before = CarryMotion(
      *lost_map_->velocity, MotionSteps(last.timestamp, after->timestamp(), lost_map_->step_seconds, 0),
      kMaxPredictedSteps, *CurrentCameraFromWorld(last) * before->world_from_camera());
  map_.AddGapLink({map_.KeyFrameById(before->id()), after, after_from_before, before->scale_correction()});
  spdlog::info(
      "map {}'s first keyframe (frame {}) is linked to keyframe {} (frame {}) of map {} by the motion before "
      "the loss over {:.1f} s: {:.2f} apart, turned {:.1f} deg",
      after->map_id(), after->frame_id(), before->id(), before->frame_id(), before->map_id(), seconds,
      after_from_before.Inverse().translation.norm(), after_from_before.RotationAngle() * 180.0 / M_PI);
}

double Tracker::StepsSinceTracked(double timestamp, int frames) const {
  return MotionSteps(last_tracked_.timestamp, timestamp, last_step_seconds_, frames);
}

void Tracker::PredictPose(FrameRecord& record, int frames) const {
  if (last_tracked_.reference == nullptr) return;
  record.reference = last_tracked_.reference;
  record.camera_from_reference =
      last_velocity_ ? CarryMotion(*last_velocity_, StepsSinceTracked(record.timestamp, frames),
                                   kMaxPredictedSteps, last_tracked_.camera_from_reference)
                     : last_tracked_.camera_from_reference;
  record.reference_scale = last_tracked_.reference_scale;
  record.source = PoseProvenance::kPredicted;
}

bool Tracker::Relocalize(Frame& frame) {
  // The last reference keyframe's best covisibles are tried first: where the camera was a moment ago.
  constexpr size_t kNearbyKeyFrames = 10;
  ScopedTimer timer(timing_, "relocalization");
  ComputeBow(frame);
  RelocalizationOptions relocalization;
  relocalization.exclude_dynamic = options_.exclude_dynamic;
  // Lost a moment ago, the camera is in the active map, near where the motion model puts it; on a loaded map
  // it may be anywhere in any map.
  // The frame being relocalized is not counted in frames_since_tracked_ yet.
  const int frames_since_tracked = frames_since_tracked_ + 1;
  const FrameRecord last = last_tracked_;
  const KeyFrame* last_reference = CurrentReference(last);
  const std::optional<Rigid3d> last_camera_from_world = CurrentCameraFromWorld(last);
  const double steps = StepsSinceTracked(frame.timestamp(), frames_since_tracked);
  if (last_reference != nullptr) {
    relocalization.map_id = last_reference->map_id();
    relocalization.nearby = last_reference->BestCovisibles(kNearbyKeyFrames);
    relocalization.nearby.insert(relocalization.nearby.begin(), map_.KeyFrameById(last_reference->id()));
    FrameRecord predicted;
    predicted.timestamp = frame.timestamp();
    PredictPose(predicted, frames_since_tracked);
    const std::optional<Rigid3d> camera_from_world = CurrentCameraFromWorld(predicted);
    relocalization.predicted = camera_from_world;
    // Once a new map has started, the lost map is searched only around the prediction.
    relocalization.by_appearance = !lost_map_.has_value();
    if (camera_from_world && last_camera_from_world) {
      const double step = last_velocity_ ? last_velocity_->translation.norm() : 0.0;
      const double depth = last_reference->SceneDepthQuantile(2);
      MotionSinceLoss motion;
      motion.last_center = last_camera_from_world->Inverse().translation;
      motion.predicted_center = camera_from_world->Inverse().translation;
      // Three times the distance the last motion would cover in the time since the last tracked frame, and
      // never less than half the scene depth.
      motion.radius = std::max(3.0 * step * std::max(1.0, steps), 0.5 * depth);
      // Two steps of the last motion, or a twentieth of the scene depth for a slow camera.
      motion.backward_tolerance = std::max(2.0 * step, 0.05 * depth);
      relocalization.plausible = [motion, id = frame.id()](const Frame& f) {
        const std::optional<std::string> refused = motion.Refuses(f.center());
        if (refused) spdlog::info("frame {}: a relocalization {} is refused", id, *refused);
        return !refused;
      };
    }
  }
  const bool ok = RelocalizeFrame(
      frame, database_, map_, [this](Frame& f) { return OptimizeFramePose(f); }, relocalization);
  if (!ok) return false;
  last_relocalization_frame_ = frame.id();
  last_relocalization_time_ = frame.timestamp();
  last_relocalization_recovered_ = relocalization.predicted.has_value();
  velocity_.reset();
  if (last_relocalization_recovered_) {
    // The mean motion over the gap, per step: the car may have sped up or turned while the camera was lost,
    // and the motion from before the loss, carried on, put the next stereo frame a quarter metre short of
    // where it was (a frame tracked on 37 points, made a keyframe, and the map bent by 4 degrees after it).
    velocity_ = last_camera_from_world && steps >= 1.0
                    ? Interpolate(Rigid3d(), frame.camera_from_world() * last_camera_from_world->Inverse(),
                                  1.0 / steps)
                    : last_velocity_;
  }
  // The reference keyframe is chosen by the local map step that follows.
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    MapPoint* p = frame.map_points[i];
    if (p != nullptr && !frame.outliers[i] && !p->observations().empty()) {
      reference_keyframe_ = p->observations().begin()->first;
      break;
    }
  }
  spdlog::info("frame {}: relocalized in map {}", frame.id(),
               reference_keyframe_ ? reference_keyframe_->map_id() : map_.active_map_id());
  return true;
}

bool Tracker::RelocalizeAfterCollapse(Frame& frame, int last_inliers) {
  // Where frames were dropped, far points still match at the old place: they hold the rotation but not the
  // position, and a pose kept there on some of them drifts on until a loop pulls it back. Tracking that goes
  // well seldom loses half its inliers from one frame to the next, so the search below is rare.
  constexpr int kCollapseRatio = 2;
  if (inliers_ * kCollapseRatio >= last_inliers) return false;
  const int tracked_inliers = inliers_;
  Frame candidate = frame;
  candidate.ClearMatches();
  // The tracked pass marked its local map as this frame's; the candidate's must gather and search it anew.
  // Points the candidate's pass meets are counted as seen (and found) a second time in this frame.
  for (KeyFrame* kf : local_keyframes_) kf->tracking_local_frame = UINT64_MAX;
  for (MapPoint* p : local_points_) p->tracking_local_map_frame = p->tracking_last_seen_frame = UINT64_MAX;
  for (MapPoint* p : frame.map_points) {
    if (p != nullptr) p->tracking_last_seen_frame = UINT64_MAX;
  }
  KeyFrame* const reference = reference_keyframe_;
  std::vector<KeyFrame*> local_keyframes = local_keyframes_;
  std::vector<MapPoint*> local_points = local_points_;
  const std::uint64_t relocalization_frame = last_relocalization_frame_;
  const double relocalization_time = last_relocalization_time_;
  const bool relocalization_recovered = last_relocalization_recovered_;
  const std::optional<Rigid3d> velocity = velocity_;
  const bool relocalized = Relocalize(candidate) && TrackLocalMap(candidate);
  if (relocalized && inliers_ > tracked_inliers) {
    spdlog::info(
        "frame {}: tracked on {} inliers after the last frame's {}; relocalized on {}: that pose is kept",
        frame.id(), tracked_inliers, last_inliers, inliers_);
    frame = std::move(candidate);
    return true;
  }
  spdlog::info("frame {}: tracked on {} inliers after the last frame's {}; the tracked pose is kept ({})",
               frame.id(), tracked_inliers, last_inliers,
               relocalized ? fmt::format("relocalized on {}", inliers_) : std::string("not relocalized"));
  reference_keyframe_ = reference;
  local_keyframes_ = std::move(local_keyframes);
  local_points_ = std::move(local_points);
  last_relocalization_frame_ = relocalization_frame;
  last_relocalization_time_ = relocalization_time;
  last_relocalization_recovered_ = relocalization_recovered;
  velocity_ = velocity;
  inliers_ = tracked_inliers;
  return false;
}

}  // namespace semslam
