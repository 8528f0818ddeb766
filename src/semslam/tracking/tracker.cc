#include "semslam/tracking/tracker.h"

#include <spdlog/spdlog.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <map>
#include <set>
#include <utility>

#include "semslam/core/error.h"
#include "semslam/features/matching.h"
#include "semslam/features/stereo_matching.h"
#include "semslam/geometry/two_view.h"
#include "semslam/map/map_matcher.h"
#include "semslam/mapping/local_mapper.h"
#include "semslam/mapping/map_optimization.h"
#include "semslam/optim/bundle_adjustment.h"
#include "semslam/optim/pose_optimization.h"
#include "semslam/place/keyframe_database.h"
#include "semslam/place/vocabulary.h"
#include "semslam/tracking/relocalization.h"

namespace semslam {

void TrackerOptions::Check() const {
  orb.Check();
  Require(init_num_features >= 0, "tracker: init_num_features must be >= 0");
  Require(init_level_share_exponent >= 0 && init_level_share_exponent <= 4,
          "tracker: init_level_share_exponent must be in [0, 4]");
  Require(max_seconds_between_keyframes > 0, "tracker: max_seconds_between_keyframes must be positive");
  Require(min_seconds_between_keyframes >= 0, "tracker: min_seconds_between_keyframes must be >= 0");
  Require(min_seconds_between_keyframes <= max_seconds_between_keyframes,
          "tracker: min_seconds_between_keyframes must not exceed max_seconds_between_keyframes");
  Require(close_depth_baselines > 0, "tracker: close_depth_baselines must be positive");
  Require(keyframe_tracked_ratio_mono > 0 && keyframe_tracked_ratio_mono <= 1 &&
              keyframe_tracked_ratio_stereo > 0 && keyframe_tracked_ratio_stereo <= 1,
          "tracker: keyframe_tracked_ratio_mono/stereo must be in (0, 1]");
  Require(keyframe_collapse_ratio_mono >= 0 && keyframe_collapse_ratio_mono <= keyframe_tracked_ratio_mono &&
              keyframe_collapse_ratio_stereo >= 0 &&
              keyframe_collapse_ratio_stereo <= keyframe_tracked_ratio_stereo,
          "tracker: keyframe_collapse_ratio_mono/stereo must be in [0, keyframe_tracked_ratio]");
  Require(keyframe_weak_inliers_mono >= 0, "tracker: keyframe_weak_inliers_mono must be >= 0");
  Require(init_min_matches >= 8, "tracker: init_min_matches must be >= 8");
  Require(init_min_parallax_deg >= 0 && init_parallax_rank >= 1 && init_min_points >= 8,
          "tracker: init_min_parallax_deg must be >= 0, init_parallax_rank >= 1, init_min_points >= 8");
  Require(init_match_max_level >= 0 && init_match_level_difference >= 0,
          "tracker: init_match_max_level and init_match_level_difference must be >= 0");
  Require(relocalization_timeout_s >= 0, "tracker: relocalization_timeout_s must be >= 0");
  Require(min_keyframes_to_keep_map >= 1, "tracker: min_keyframes_to_keep_map must be >= 1");
  Require(motion_model_min_kept_ratio >= 0 && motion_model_min_kept_ratio <= 1,
          "tracker: motion_model_min_kept_ratio must be in [0, 1]");
}

const char* ToString(PoseProvenance source) {
  switch (source) {
    case PoseProvenance::kNone:
      return "none";
    case PoseProvenance::kTracked:
      return "tracked";
    case PoseProvenance::kInterpolated:
      return "interpolated";
    case PoseProvenance::kPredicted:
      return "predicted";
  }
  return "?";
}

const char* ToString(TrackingState state) {
  switch (state) {
    case TrackingState::kNotInitialized:
      return "not initialized";
    case TrackingState::kOk:
      return "ok";
    case TrackingState::kLost:
      return "lost";
  }
  return "?";
}

Tracker::Tracker(const TrackerOptions& options, const PinholeCamera& camera, std::optional<StereoRig> stereo,
                 Map& map, const Vocabulary& vocabulary, KeyFrameDatabase& database, LocalMapper* mapper,
                 TimingRegistry& timing)
    : options_(options),
      camera_(camera),
      stereo_(std::move(stereo)),
      map_(map),
      vocabulary_(vocabulary),
      database_(database),
      mapper_(mapper),
      timing_(timing) {
  options_.Check();
  camera_.Check();
  Require(options_.monocular || stereo_.has_value(), "tracker: stereo mode needs a stereo rig");
  extractor_ = std::make_unique<OrbExtractor>(options_.orb);
  if (!options_.monocular) right_extractor_ = std::make_unique<OrbExtractor>(options_.orb);
  OrbOptions init = options_.orb;
  init.num_features =
      options_.init_num_features > 0 ? options_.init_num_features : 2 * options_.orb.num_features;
  init.level_share_exponent = options_.init_level_share_exponent;
  init_extractor_ = std::make_unique<OrbExtractor>(init);
}

Tracker::~Tracker() = default;

void Tracker::SetMapLoaded() {
  map_loaded_ = true;
  state_ = TrackingState::kLost;
}

void Tracker::SetCamera(const PinholeCamera& camera) {
  Require(records_.empty(), "tracker: the camera can only be set before the first frame");
  camera.Check();
  camera_ = camera;
}

void Tracker::ForgetTrackingState() {
  state_ = TrackingState::kNotInitialized;
  last_frame_.reset();
  velocity_.reset();
  lost_since_.reset();
  map_loaded_ = false;
  last_keyframe_ = reference_keyframe_ = nullptr;
  local_keyframes_.clear();
  local_points_.clear();
  last_tracked_inliers_ = 0;
}

void Tracker::Reset() {
  ForgetTrackingState();
  init_frame_.reset();
  init_between_frames_.clear();
  last_tracked_.reference = nullptr;
  last_velocity_.reset();
  const bool lost_map_kept = lost_map_ && [&] {
    auto lock = map_.ReadLock();
    return CurrentReference(lost_map_->last_tracked) != nullptr;  // the keyframe, or a good ancestor of it
  }();
  if (lost_map_kept) {
    // The map given up was the one started after a loss: the lost map is searched again first, from where
    // it was left.
    last_tracked_ = lost_map_->last_tracked;
    last_velocity_ = lost_map_->velocity;
    last_step_seconds_ = lost_map_->step_seconds;
    frames_since_tracked_ = static_cast<int>(records_.size() - 1 - lost_map_->record_index);
  } else {
    lost_map_.reset();
  }
}

std::shared_ptr<const FrameData> Tracker::ExtractFeatures(const cv::Mat& left, const cv::Mat& right,
                                                          const cv::Mat& mask, bool initialization) {
  ScopedTimer timer(timing_, "orb_extraction");
  const OrbExtractor& extractor = initialization ? *init_extractor_ : *extractor_;
  FeatureSet left_features, right_features;
  if (right.empty()) {
    left_features = extractor.Extract(left, mask);
    return MakeFrameData(camera_, stereo_, std::move(left_features), {}, {});
  }
  tbb::parallel_invoke([&] { left_features = extractor_->Extract(left, mask); },
                       [&] { right_features = right_extractor_->Extract(right); });
  StereoMatches stereo = MatchStereo(left_features, right_features, left, right, *stereo_);
  return MakeFrameData(camera_, stereo_, std::move(left_features), std::move(stereo.right_u),
                       std::move(stereo.depth));
}

namespace {

// The good keyframe a record hangs from, and the frame's pose relative to it.
std::pair<const KeyFrame*, Rigid3d> ResolveReference(const FrameRecord& record) {
  return GoodAncestor(record.reference, record.camera_from_reference, record.reference_scale);
}

}  // namespace

std::optional<Rigid3d> CurrentCameraFromWorld(const FrameRecord& record) {
  const auto [kf, camera_from_kf] = ResolveReference(record);
  if (kf == nullptr) return std::nullopt;
  return camera_from_kf * kf->camera_from_world();
}

const KeyFrame* CurrentReference(const FrameRecord& record) { return ResolveReference(record).first; }

TrackingResult Tracker::Track(std::uint64_t frame_id, double timestamp, const cv::Mat& left,
                              const cv::Mat& right, const cv::Mat& mask) {
  Stopwatch watch;
  new_keyframes_.clear();
  tracked_camera_from_reference_.reset();
  const bool mono_init = options_.monocular && state_ == TrackingState::kNotInitialized;
  Frame frame(frame_id, timestamp,
              ExtractFeatures(left, options_.monocular ? cv::Mat() : right, mask, mono_init));
  TrackingResult result;

  // A map lost for good whose successor has not started: relocalization there comes before a new map.
  const bool recovering = state_ == TrackingState::kNotInitialized && lost_map_.has_value();
  if (state_ == TrackingState::kNotInitialized && !recovering) {
    if (InitializeMap(frame)) {
      state_ = TrackingState::kOk;
      result.initialized_now = true;
    }
  } else if (TrackInMap(frame, result)) {
    state_ = TrackingState::kOk;
    lost_since_.reset();
    if (recovering) {
      auto lock = map_.ReadLock();
      spdlog::info("frame {}: map {} found again after {:.1f} s; no new map needed", frame.id(),
                   reference_keyframe_->map_id(), timestamp - lost_map_->last_tracked.timestamp);
      lost_map_.reset();
    }
  } else if (recovering) {
    if (InitializeMap(frame)) {
      state_ = TrackingState::kOk;
      result.initialized_now = true;
    }
  } else {
    state_ = TrackingState::kLost;
    velocity_.reset();
    if (!lost_since_) {
      lost_since_ = timestamp;
      spdlog::info("frame {}: tracking lost", frame.id());
    }
  }

  if (state_ == TrackingState::kLost && !options_.localization_only) {
    size_t active_keyframes = 0;
    {
      auto lock = map_.ReadLock();
      active_keyframes = map_.NumKeyFramesOfMap(map_.active_map_id());
    }
    if (!map_loaded_ && active_keyframes < static_cast<size_t>(options_.min_keyframes_to_keep_map)) {
      spdlog::warn("frame {}: tracking lost soon after initialization; that map ({} keyframes) is given up",
                   frame.id(), active_keyframes);
      result.reset_requested = true;
    } else if (timestamp - lost_since_.value_or(timestamp) >= options_.relocalization_timeout_s) {
      StartNewMap(frame, result);
    }
  }

  FrameRecord record;
  record.frame_id = frame.id();
  record.timestamp = timestamp;
  if (state_ == TrackingState::kOk && frame.has_pose()) {
    if (frame.reference_keyframe == nullptr) frame.reference_keyframe = reference_keyframe_;
    record.reference = frame.reference_keyframe;
    record.source = PoseProvenance::kTracked;
    auto lock = map_.ReadLock();
    FollowMapChange(frame);
    record.camera_from_reference = frame.camera_from_world() * record.reference->world_from_camera();
    record.reference_scale = record.reference->scale_correction();
    result.camera_from_world = frame.camera_from_world();
    result.map_id = record.reference->map_id();
    result.matched_points = inliers_;
    const bool previous_tracked = frames_since_tracked_ == 0 && last_tracked_.reference != nullptr;
    if (previous_tracked) last_step_seconds_ = timestamp - last_tracked_.timestamp;
    last_tracked_ = record;
    last_velocity_ = velocity_;
    frames_since_tracked_ = 0;
  } else {
    ++frames_since_tracked_;
    PredictPose(record, frames_since_tracked_);
  }
  records_.push_back(record);
  result.state = state_;
  result.new_keyframes = new_keyframes_;
  if (result.relocalized) ++num_relocalizations_;
  last_frame_ = std::make_unique<Frame>(std::move(frame));
  HandKeyFramesToMapper();
  result.milliseconds = watch.ElapsedMs();
  timing_.Add("tracking", result.milliseconds);
  return result;
}

void Tracker::HandKeyFramesToMapper() {
  if (keyframes_for_mapper_.empty()) return;
  for (KeyFrame* kf : keyframes_for_mapper_) mapper_->InsertKeyFrame(kf);
  keyframes_for_mapper_.clear();
  if (holding_mapper_) mapper_->SetNotStop(false);
  holding_mapper_ = false;
}

bool Tracker::TrackInMap(Frame& frame, TrackingResult& result) {
  auto lock = map_.ReadLock();
  if (last_frame_) ReplaceMergedPoints(*last_frame_);
  bool ok = false;
  const bool was_tracking = state_ == TrackingState::kOk;
  const int last_inliers = std::exchange(last_tracked_inliers_, 0);
  if (was_tracking) {
    const bool map_changed = map_.big_change_index() != last_big_change_;
    if (map_changed) {
      last_big_change_ = map_.big_change_index();
      // A loop correction or global BA moved the map under the last frame: it follows its reference
      // keyframe, or the search below would start metres off (3.5 m errors at a corner of the city).
      const auto corrected = records_.empty() ? std::nullopt : CurrentCameraFromWorld(records_.back());
      if (last_frame_ && corrected) last_frame_->SetPose(*corrected);
      // A monocular merge or loop may have rescaled the map there: the motion per frame stretches with it.
      const KeyFrame* reference = records_.empty() ? nullptr : records_.back().reference;
      if (velocity_ && reference != nullptr && !reference->is_bad()) {
        velocity_ = Stretched(*velocity_, reference->scale_correction() / records_.back().reference_scale);
      }
    }
    // Right after a relocalization the motion is unknown, unless it was a recovery (the mean motion over the
    // gap goes on).
    const bool just_relocalized =
        frame.id() < last_relocalization_frame_ + 2 && !last_relocalization_recovered_;
    // After a loop correction or a merge the motion model still holds (the last frame moved with its
    // keyframe), and is checked against the reference keyframe when it keeps few points.
    if (!velocity_ || just_relocalized) {
      ok = TrackReferenceKeyFrame(frame) > 0;
    } else {
      ok = TrackWithMotionModelOrReference(frame);
    }
  } else {
    ok = Relocalize(frame);
  }
  if (!ok || !TrackLocalMap(frame)) {
    // A map started on this frame must not inherit the points it was matched to here: a refused
    // relocalization left a monocular map's first keyframes holding the lost map's points, and the new map,
    // tied to another map's frame, shrank 3.7 times over its first 40 frames.
    frame.ClearMatches();
    return false;
  }
  const bool relocalized_after_collapse = was_tracking && RelocalizeAfterCollapse(frame, last_inliers);
  result.relocalized = !was_tracking || relocalized_after_collapse;  // confirmed by the local map
  if (reference_keyframe_->map_id() != map_.active_map_id()) {
    // Relocalized in another map (of a loaded atlas, or the one lost before the active one started):
    // tracking and mapping go on in that one.
    lock.unlock();
    {
      auto write = map_.WriteLock();
      map_.ActivateMap(reference_keyframe_->map_id());
    }
    lock.lock();
  }
  if (frame.reference_keyframe == nullptr) frame.reference_keyframe = reference_keyframe_;
  tracked_camera_from_reference_ = frame.camera_from_world() * frame.reference_keyframe->world_from_camera();
  if (!relocalized_after_collapse && last_frame_ && last_frame_->has_pose() &&
      last_frame_->reference_keyframe != nullptr) {
    velocity_ = frame.camera_from_world() * last_frame_->world_from_camera();
  } else if (!result.relocalized || !last_relocalization_recovered_) {
    velocity_.reset();  // a recovered frame keeps the mean motion over the gap (Relocalize)
  }
  if (NeedNewKeyFrame(frame)) {
    lock.unlock();
    CreateNewKeyFrame(frame);
    result.new_keyframe = true;
  }
  last_tracked_inliers_ = inliers_;
  // Outliers are not carried to the next frame's motion-model search.
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    if (frame.outliers[i]) frame.map_points[i] = nullptr;
  }
  return true;
}

void Tracker::FollowMapChange(Frame& frame) const {
  if (map_.big_change_index() == last_big_change_ || !tracked_camera_from_reference_) return;
  frame.SetPose(*tracked_camera_from_reference_ * frame.reference_keyframe->camera_from_world());
}

void Tracker::ReplaceMergedPoints(Frame& frame) const {
  for (auto& p : frame.map_points) {
    if (p != nullptr) {
      MapPoint* resolved = p->Resolve();
      p = resolved->is_bad() ? nullptr : resolved;
    }
  }
}

int Tracker::DiscardOutliers(Frame& frame) const {
  int good = 0;
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    if (frame.map_points[i] == nullptr) continue;
    if (frame.outliers[i]) {
      frame.map_points[i] = nullptr;
      frame.outliers[i] = false;
    } else if (frame.map_points[i]->num_observations() > 0) {
      ++good;
    }
  }
  return good;
}

int Tracker::DropDynamicMatches(Frame& frame) const {
  int kept = 0;
  for (auto& p : frame.map_points) {
    if (p == nullptr) continue;
    if (options_.exclude_dynamic && p->IsDynamic()) {
      p = nullptr;
    } else {
      ++kept;
    }
  }
  return kept;
}

void Tracker::ComputeBow(Frame& frame) const {
  if (frame.has_bow) return;
  vocabulary_.Transform(frame.features().descriptors, &frame.bow, &frame.feature_vector);
  frame.has_bow = true;
}

int Tracker::OptimizeFramePose(Frame& frame) {
  ScopedTimer timer(timing_, "pose_optimization");
  PoseOptimizationProblem problem;
  problem.camera = frame.data().camera;
  problem.camera_from_world = frame.camera_from_world();
  const auto& data = frame.data();
  std::vector<size_t> slots;
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    MapPoint* p = frame.map_points[i];
    if (p == nullptr) continue;
    if (options_.exclude_dynamic && p->IsDynamic()) {
      frame.map_points[i] = nullptr;
      continue;
    }
    const Keypoint& kp = data.features.keypoints[i];
    PoseObservation obs;
    obs.point = p->position();
    obs.pixel = kp.pixel.cast<double>();
    obs.right_u = (!data.right_u.empty() && data.right_u[i] >= 0) ? data.right_u[i] : -1.0;
    obs.inv_sigma2 = data.features.pyramid.inv_sigma2[kp.level];
    problem.observations.push_back(obs);
    slots.push_back(i);
  }
  if (data.stereo) problem.baseline = data.stereo->baseline;
  if (problem.observations.size() < 3) return 0;
  const PoseOptimizationResult result = OptimizePose(problem);
  frame.SetPose(result.camera_from_world);
  int inliers = 0;
  for (size_t k = 0; k < slots.size(); ++k) {
    frame.outliers[slots[k]] = !result.inliers[k];
    inliers += result.inliers[k] ? 1 : 0;
  }
  return inliers;
}

void Tracker::UpdateLocalMap(Frame& frame) {
  // Keyframes that see the frame's points, weighted by how many they see.
  std::map<KeyFrame*, int, ById> counter;
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    MapPoint* p = frame.map_points[i];
    if (p == nullptr) continue;
    if (p->is_bad()) {
      frame.map_points[i] = nullptr;
      continue;
    }
    for (const auto& [kf, index] : p->observations()) ++counter[kf];
  }
  if (counter.empty()) return;
  local_keyframes_.clear();
  KeyFrame* best = nullptr;
  int best_count = 0;
  for (const auto& [kf, count] : counter) {
    if (kf->is_bad()) continue;
    if (count > best_count) {
      best_count = count;
      best = kf;
    }
    local_keyframes_.push_back(kf);
    kf->tracking_local_frame = frame.id();
  }
  // Neighbours, children and parent of those keyframes, up to 80 in all.
  const size_t direct = local_keyframes_.size();
  for (size_t k = 0; k < direct && local_keyframes_.size() < 80; ++k) {
    KeyFrame* kf = local_keyframes_[k];
    auto add = [&](KeyFrame* other) {
      if (other == nullptr || other->is_bad() || other->tracking_local_frame == frame.id()) return false;
      local_keyframes_.push_back(other);
      other->tracking_local_frame = frame.id();
      return true;
    };
    for (KeyFrame* neighbour : kf->BestCovisibles(10)) {
      if (add(neighbour)) break;
    }
    for (KeyFrame* child : kf->children()) {
      if (add(child)) break;
    }
    add(kf->parent());
  }
  if (best != nullptr) {
    reference_keyframe_ = best;
    frame.reference_keyframe = best;
  }
  local_points_.clear();
  for (KeyFrame* kf : local_keyframes_) {
    for (MapPoint* p : kf->map_points()) {
      if (p == nullptr || p->is_bad() || p->tracking_local_map_frame == frame.id()) continue;
      p->tracking_local_map_frame = frame.id();
      local_points_.push_back(p);
    }
  }
}

void Tracker::SearchLocalMapPoints(Frame& frame) {
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    MapPoint* p = frame.map_points[i];
    if (p == nullptr) continue;
    if (p->is_bad()) {
      frame.map_points[i] = nullptr;
      continue;
    }
    p->IncreaseVisible();
    p->tracking_last_seen_frame = frame.id();
    p->track_in_view = false;
  }
  const FrameData& data = frame.data();
  const Eigen::Vector3d center = frame.center();
  int to_match = 0;
  for (MapPoint* p : local_points_) {
    p->track_in_view = false;
    if (p->tracking_last_seen_frame == frame.id() || p->is_bad()) continue;
    if (options_.exclude_dynamic && p->IsDynamic()) continue;
    const Eigen::Vector3d in_camera = frame.camera_from_world() * p->position();
    if (in_camera.z() <= 0) continue;
    const Eigen::Vector2d uv = data.camera.Project(in_camera);
    if (!data.InBounds(static_cast<float>(uv.x()), static_cast<float>(uv.y()))) continue;
    const Eigen::Vector3d ray = p->position() - center;
    const float distance = static_cast<float>(ray.norm());
    if (distance < p->min_distance() || distance > p->max_distance()) continue;
    const float view_cos = static_cast<float>(ray.dot(p->normal()) / distance);
    if (view_cos < 0.5f) continue;
    p->track_in_view = true;
    p->track_u = static_cast<float>(uv.x());
    p->track_v = static_cast<float>(uv.y());
    p->track_right_u = data.stereo ? static_cast<float>(data.stereo->ProjectRightU(in_camera)) : -1.0f;
    p->track_level = p->PredictLevel(distance, data.features.pyramid);
    p->track_view_cos = view_cos;
    p->IncreaseVisible();
    ++to_match;
  }
  if (to_match == 0) return;
  float radius = options_.monocular ? 1.0f : 3.0f;
  if (frame.id() < last_relocalization_frame_ + 2) radius = 5.0f;
  SearchLocalPoints(frame, local_points_, radius);
}

bool Tracker::TrackLocalMap(Frame& frame) {
  ScopedTimer timer(timing_, "track_local_map");
  const int before_local = frame.CountMatches();
  UpdateLocalMap(frame);
  SearchLocalMapPoints(frame);
  const int after_local = frame.CountMatches();
  std::fill(frame.outliers.begin(), frame.outliers.end(), false);
  OptimizeFramePose(frame);
  inliers_ = 0;
  for (size_t i = 0; i < frame.map_points.size(); ++i) {
    MapPoint* p = frame.map_points[i];
    if (p == nullptr) continue;
    if (!frame.outliers[i]) {
      p->IncreaseFound();
      if (p->num_observations() > 0 || options_.localization_only) ++inliers_;
    } else if (!options_.monocular) {
      frame.map_points[i] = nullptr;
    }
  }
  // Right after a relocalization the local map must confirm it, more firmly than tracking needs, unless it
  // was a recovery near the prediction (see last_relocalization_recovered_).
  if (spdlog::should_log(spdlog::level::debug)) {
    const auto in_view = std::count_if(local_points_.begin(), local_points_.end(),
                                       [](const MapPoint* p) { return p->track_in_view; });
    spdlog::debug(
        "frame {}: {} matched before the local map; local map {} keyframes, {} points, {} in view; {} "
        "matched, {} inliers",
        frame.id(), before_local, local_keyframes_.size(), local_points_.size(), in_view, after_local,
        inliers_);
  }
  constexpr int kTracked = 30, kRelocalized = 50, kRecovered = 20;
  const bool after_relocalization =
      !SecondsReached(frame.timestamp() - last_relocalization_time_, options_.max_seconds_between_keyframes);
  if (!after_relocalization) return inliers_ >= kTracked;
  return inliers_ >= (last_relocalization_recovered_ ? kRecovered : kRelocalized);
}

}  // namespace semslam
