#include "semslam/system/slam_system.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <map>
#include <thread>

#include "semslam/core/error.h"
#include "semslam/mapping/map_optimization.h"
#include "semslam/place/keyframe_database.h"
#include "semslam/place/vocabulary.h"
#include "semslam/semantics/label_fusion.h"

namespace semslam {

std::optional<SensorMode> ParseSensorMode(std::string_view name) {
  if (name == "mono") return SensorMode::kMonocular;
  if (name == "stereo") return SensorMode::kStereo;
  return std::nullopt;
}

std::optional<Pacing> ParsePacing(std::string_view name) {
  if (name == "fast") return Pacing::kFast;
  if (name == "realtime") return Pacing::kRealtime;
  if (name == "synchronous") return Pacing::kSynchronous;
  return std::nullopt;
}

std::string_view PacingName(Pacing pacing) {
  switch (pacing) {
    case Pacing::kFast:
      return "fast";
    case Pacing::kRealtime:
      return "realtime";
    case Pacing::kSynchronous:
      return "synchronous";
  }
  return "realtime";
}

namespace {

// A map's nominal camera is the sensor a sequence has when their images and intrinsics agree; a refined map's
// when their distortion does too (none: a refinement is made only for a camera without). An unrefined map
// read from a file of version 2 knows its sensor's intrinsics only (its keyframes' camera), so its distortion
// is not compared.
bool SameSensor(const PinholeCamera& sequence, const MapCamera& map, double tolerance_px) {
  const PinholeCamera& nominal = map.nominal;
  const bool same_intrinsics = sequence.width == nominal.width && sequence.height == nominal.height &&
                               std::abs(sequence.fx - nominal.fx) <= tolerance_px &&
                               std::abs(sequence.fy - nominal.fy) <= tolerance_px &&
                               std::abs(sequence.cx - nominal.cx) <= tolerance_px &&
                               std::abs(sequence.cy - nominal.cy) <= tolerance_px;
  if (!same_intrinsics || !map.refined()) return same_intrinsics;
  const Distortion &a = sequence.distortion, &b = nominal.distortion;
  constexpr double kTolerance = 1e-9;
  return std::abs(a.k1 - b.k1) <= kTolerance && std::abs(a.k2 - b.k2) <= kTolerance &&
         std::abs(a.p1 - b.p1) <= kTolerance && std::abs(a.p2 - b.p2) <= kTolerance &&
         std::abs(a.k3 - b.k3) <= kTolerance;
}

}  // namespace

TrackingCameraChoice ChooseTrackingCamera(const PinholeCamera& sequence, bool stereo,
                                          const std::map<std::uint32_t, MapCamera>& cameras,
                                          const std::map<std::uint32_t, size_t>& keyframes_per_map,
                                          bool* other_sensor, double tolerance_px) {
  if (other_sensor != nullptr) *other_sensor = false;
  TrackingCameraChoice choice{sequence, std::nullopt, ""};
  std::optional<std::uint32_t> largest;
  size_t most = 0;
  for (const auto& [map_id, count] : keyframes_per_map) {
    if (count > most && cameras.count(map_id)) {
      most = count;
      largest = map_id;
    }
  }
  if (!largest) {
    choice.reason = "the sequence's own: no loaded map has a camera";
    return choice;
  }
  const MapCamera& map = cameras.at(*largest);
  if (!SameSensor(sequence, map, tolerance_px)) {
    if (other_sensor != nullptr) *other_sensor = true;
    choice.reason = fmt::format("the sequence's own: it is another camera than map {}'s ({} against {})",
                                *largest, sequence.ToString(), map.nominal.ToString());
  } else if (!map.refined()) {
    choice.reason = fmt::format("the sequence's own: map {} keeps the nominal camera", *largest);
  } else if (stereo) {
    choice.reason = fmt::format(
        "the sequence's own: a stereo session keeps its rectified pair, not map {}'s refined camera",
        *largest);
  } else {
    choice.camera = map.camera;
    choice.map_id = *largest;
    choice.reason = fmt::format(
        "map {}'s refined camera: the map was fitted to it, and the sequence's camera is "
        "its nominal one",
        *largest);
  }
  return choice;
}

void SlamOptions::Check() const {
  Require(max_queued_keyframes >= 0, "max_queued_keyframes must be >= 0");
  Require(std::isfinite(realtime_wait_for_mapping_frames) && realtime_wait_for_mapping_frames >= 0 &&
              realtime_wait_for_mapping_frames <= 10,
          "realtime_wait_for_mapping_frames must be in [0, 10]");
  Require(final_global_ba_iterations >= 1, "final_global_ba_iterations must be >= 1");
  Require(final_global_ba_refine_iterations >= 1, "final_global_ba_refine_iterations must be >= 1");
  Require(std::isfinite(final_refine_intrinsics_min_reduction) &&
              final_refine_intrinsics_min_reduction >= 0 && final_refine_intrinsics_min_reduction < 1,
          "final_refine_intrinsics_min_reduction must be in [0, 1)");
  Require(final_refine_intrinsics_min_keyframes >= 3,
          "final_refine_intrinsics_min_keyframes must be at least 3");
  tracker.Check();
  mapper.Check();
  loop.Check();
}

SlamSystem::SlamSystem(const SlamOptions& options, const PinholeCamera& camera,
                       std::optional<StereoRig> stereo)
    : options_(options),
      camera_(camera),
      stereo_(std::move(stereo)),
      tracking_camera_{camera, std::nullopt, "the sequence's own: no map loaded"} {
  options_.tracker.monocular = options_.mode == SensorMode::kMonocular;
  options_.mapper.monocular = options_.tracker.monocular;
  options_.loop.fix_scale = !options_.tracker.monocular;
  options_.tracker.localization_only = options_.localization_only;
  options_.tracker.exclude_dynamic = options_.exclude_dynamic;
  options_.mapper.exclude_dynamic = options_.exclude_dynamic;
  options_.mapper.yield_to_new_keyframes = options_.pacing != Pacing::kSynchronous;
  options_.loop.global_ba_low_priority = options_.pacing != Pacing::kSynchronous;
  options_.Check();
  Require(options_.mode == SensorMode::kMonocular || stereo_.has_value(),
          "stereo mode needs a sequence with a right camera and a baseline");
  const std::filesystem::path vocabulary_path =
      options_.vocabulary.empty() ? DefaultVocabularyPath() : options_.vocabulary;
  Stopwatch watch;
  vocabulary_ = std::make_unique<Vocabulary>(Vocabulary::Load(vocabulary_path));
  spdlog::info("vocabulary {} loaded in {:.0f} ms", vocabulary_path.string(), watch.ElapsedMs());
  database_ = std::make_unique<KeyFrameDatabase>(vocabulary_->size());
  map_ = std::make_unique<Map>();
  mapper_ = std::make_unique<LocalMapper>(options_.mapper, *map_, *vocabulary_, *database_, timing_);
  loop_closer_ =
      std::make_unique<LoopCloser>(options_.loop, *map_, *vocabulary_, *database_, *mapper_, timing_);
  if (options_.mode == SensorMode::kStereo) {
    merge_verifier_ = std::make_unique<MergeVerifier>(no_world_maps_);
    loop_closer_->SetPlaceCheck(
        [this](const KeyFrame& current, const KeyFrame& matched, const Sim3d& transform) {
          return current.map_id() == matched.map_id() || (*merge_verifier_)(current, matched, transform);
        });
  }
  mapper_->AddKeyFrameListener([this](KeyFrame* kf) { loop_closer_->InsertKeyFrame(kf); });
  tracker_ = std::make_unique<Tracker>(options_.tracker, camera_, stereo_, *map_, *vocabulary_, *database_,
                                       options_.localization_only ? nullptr : mapper_.get(), timing_);
  if (!options_.localization_only) {
    mapper_->Start();
    loop_closer_->Start();
  }
}

SlamSystem::~SlamSystem() { Finish(); }

void SlamSystem::EnableSegmentation(std::shared_ptr<Segmenter> segmenter) {
  Require(frames_ == 0, "segmentation must be enabled before the first frame");
  if (!segmenter) return;
  spdlog::info("segmentation: {}", segmenter->Describe());
  segmentation_ = std::make_unique<SegmentationWorker>(
      std::move(segmenter), [this](SegmentationResult&& result) { OnSegmentation(std::move(result)); });
}

std::optional<SegmentationWorkerStats> SlamSystem::SegmentationStats() const {
  if (!segmentation_) return std::nullopt;
  return segmentation_->stats();
}

namespace {
// Request ids of frames that are not keyframes: the frame index with the top bit set.
constexpr std::uint64_t kFrameRequest = std::uint64_t{1} << 63;
}  // namespace

void SlamSystem::OnSegmentation(SegmentationResult&& result) {
  ScopedTimer timer(timing_, "label_fusion");
  if (result.keyframe_id & kFrameRequest) {
    FrameObservations observations;
    {
      std::lock_guard pending(pending_frames_mutex_);
      const auto it = pending_frames_.find(result.keyframe_id);
      if (it == pending_frames_.end()) return;
      observations = std::move(it->second);
      pending_frames_.erase(it);
    }
    auto lock = map_->WriteLock();
    std::vector<float> rows;
    SampleAtPixels(result.segmentation, observations.pixels, &rows);
    for (size_t k = 0; k < observations.points.size(); ++k) {
      MapPoint* point = observations.points[k]->Resolve();
      if (!point->is_bad()) FuseSampledObservation(point->labels(), rows.data() + k * kNumClasses);
    }
    ++segmented_frames_;
    return;
  }
  auto lock = map_->WriteLock();
  KeyFrame* keyframe = map_->KeyFrameById(result.keyframe_id);
  if (keyframe == nullptr || keyframe->is_bad()) return;  // culled while it was being segmented
  // What the segmentation says at every keypoint, for points that gain an observation here later...
  std::vector<float> rows;
  SampleAtKeypoints(
      result.segmentation, keyframe->features().keypoints,
      [](const Keypoint& keypoint) { return keypoint.pixel; }, &rows);
  keyframe->keypoint_labels.Assign(rows);
  // ...and the points it sees now, projected into it (eqs. 1-2) and fused (eqs. 3-6).
  std::vector<PointObservation> points;
  for (MapPoint* point : keyframe->map_points()) {
    if (point != nullptr && !point->is_bad()) points.push_back({point->position(), &point->labels()});
  }
  FuseKeyframeObservations(result.segmentation, keyframe->camera_from_world(), keyframe->camera(), points);
  ++segmented_keyframes_;
}

MapFileContents SlamSystem::LoadMap(const std::filesystem::path& path) {
  Require(frames_ == 0, "a map can only be loaded before the first frame");
  auto lock = map_->WriteLock();
  MapFileContents contents = ReadMapFile(path, *map_);
  for (KeyFrame* kf : map_->KeyFrames()) {
    vocabulary_->Transform(kf->features().descriptors, &kf->bow, &kf->feature_vector);
    kf->has_bow = true;
    database_->Add(kf->id(), kf->bow);
  }
  map_->BeginSession("", "");
  spdlog::info("map {} loaded: {} keyframes, {} points, {} maps, {} sessions", path.string(),
               map_->NumKeyFrames(), map_->NumMapPoints(), map_->MapIds().size(),
               map_->sessions().size() - 1);
  map_cameras_ = contents.cameras;
  std::map<std::uint32_t, size_t> keyframes_per_map;
  for (const std::uint32_t map_id : map_->MapIds())
    keyframes_per_map[map_id] = map_->NumKeyFramesOfMap(map_id);
  bool other_sensor = false;
  tracking_camera_ = ChooseTrackingCamera(camera_, options_.mode == SensorMode::kStereo, map_cameras_,
                                          keyframes_per_map, &other_sensor);
  if (other_sensor) {
    spdlog::warn(
        "{}: frames are undistorted with {}; the map's poses and points were fitted to its own camera",
        path.string(), tracking_camera_.reason);
  } else {
    const Distortion& d = tracking_camera_.camera.distortion;
    spdlog::info("camera: {} ({}, k1 {:.4f}, k2 {:.4f})", tracking_camera_.reason,
                 tracking_camera_.camera.ToString(), d.k1, d.k2);
  }
  if (tracking_camera_.map_id) tracker_->SetCamera(tracking_camera_.camera);
  tracker_->SetMapLoaded();
  return contents;
}

MapFileContents SlamSystem::AppendMap(const std::filesystem::path& path) {
  Require(frames_ == 0, "a map can only be appended before the first frame");
  auto lock = map_->WriteLock();
  MapFileContents contents = AppendMapFile(path, *map_);
  size_t keyframes = 0;
  for (KeyFrame* kf : map_->KeyFrames()) {
    if (kf->has_bow) continue;
    vocabulary_->Transform(kf->features().descriptors, &kf->bow, &kf->feature_vector);
    kf->has_bow = true;
    database_->Add(kf->id(), kf->bow);
    ++keyframes;
  }
  for (const auto& [map_id, camera] : contents.cameras) map_cameras_[map_id] = camera;
  spdlog::info("map {} appended: {} keyframes in {} sessions (the atlas: {} keyframes, {} maps)",
               path.string(), keyframes, map_->sessions().size() - contents.first_session,
               map_->NumKeyFrames(), map_->MapIds().size());
  return contents;
}

MapCamera SlamSystem::SessionCamera() const {
  if (tracking_camera_.map_id) return map_cameras_.at(*tracking_camera_.map_id);
  return {camera_, camera_};
}

std::map<std::uint32_t, MapCamera> SlamSystem::MapCameras() const {
  auto lock = map_->ReadLock();
  std::map<std::uint32_t, MapCamera> cameras;
  for (const std::uint32_t map_id : map_->MapIds()) {
    const auto it = map_cameras_.find(map_id);
    cameras[map_id] = it != map_cameras_.end() ? it->second : SessionCamera();
  }
  return cameras;
}

void SlamSystem::NameSession(const std::string& name, const std::string& source) {
  auto lock = map_->WriteLock();
  map_->NameCurrentSession(name, source);
}

void SlamSystem::SaveMap(const std::filesystem::path& path, const MapFileContents& extra) const {
  MapFileContents contents = extra;
  contents.cameras.merge(MapCameras());  // the caller's come first
  auto lock = map_->ReadLock();
  WriteMapFile(path, *map_, contents);
}

TrackingResult SlamSystem::ProcessFrame(std::uint64_t frame_id, double timestamp, const cv::Mat& left,
                                        const cv::Mat& right, const cv::Mat& mask, const cv::Mat& color) {
  Require(!finished_, "ProcessFrame after Finish");
  // Keyframe gaps and the pacing are measured in these stamps: they must be seconds, increasing.
  Require(std::isfinite(timestamp), fmt::format("frame {}: the timestamp is not finite", frame_id));
  if (last_timestamp_ && !(timestamp > *last_timestamp_)) {
    throw InvalidArgument(fmt::format("frame {}: timestamp {} does not follow the last frame's ({})",
                                      frame_id, timestamp, *last_timestamp_));
  }
  last_timestamp_ = timestamp;
  if (options_.pacing == Pacing::kRealtime) {
    pacer_.Wait(timestamp);  // no faster than the camera recorded
    const double slack_s = pacer_.SlackSeconds(options_.realtime_wait_for_mapping_frames);
    if (slack_s > 0 && !mapper_->IsIdle()) {
      ScopedTimer timer(timing_, "waiting_for_keyframe_mapping");
      mapper_->WaitUntilIdleFor(slack_s);
    }
  }
  TrackingResult result = tracker_->Track(frame_id, timestamp, left, right, mask);
  ++frames_;
  if (result.state == TrackingState::kOk) ++tracked_;
  const cv::Mat& segmented_image = color.empty() ? left : color;
  if (options_.pacing == Pacing::kSynchronous) {
    WaitForMappingAndLoopClosing(result);
    if (result.reset_requested) DiscardActiveMap();
    if (segmentation_) SubmitForSegmentation(frame_id, segmented_image, result);
    return result;
  }
  if (segmentation_) SubmitForSegmentation(frame_id, segmented_image, result);
  if (result.reset_requested) DiscardActiveMap();
  if (options_.max_queued_keyframes > 0 && result.new_keyframe && !options_.localization_only) {
    ScopedTimer timer(timing_, "waiting_for_mapping");
    mapper_->WaitForQueueAtMost(static_cast<size_t>(options_.max_queued_keyframes));
  }
  return result;
}

void SlamSystem::WaitForMappingAndLoopClosing(const TrackingResult& result) {
  if (options_.localization_only) return;
  // The loop closer takes each keyframe once the mapper is done with it; it, a correction or merge it makes
  // (which holds the mapper) and the global BA it then starts are waited for too, so that a drive played
  // this way sees them as instant and the next frame always meets the map they leave. Going on during a
  // correction, tracking could add no keyframe while the mapper was held and drove off its points (seed
  // 8888's merge after a black-out: two frames lost); during a global BA, what tracking met depended on how
  // far the BA had come. Only keyframes give the two threads work.
  if (result.new_keyframe || result.initialized_now || !result.new_keyframes.empty()) {
    {
      ScopedTimer timer(timing_, "waiting_for_keyframe_mapping");
      mapper_->WaitUntilIdle();
    }
    ScopedTimer timer(timing_, "waiting_for_loop_closing");
    loop_closer_->WaitUntilIdle();
  }
  mapper_->WaitWhilePaused();  // returns at once when nothing holds it
}

void SlamSystem::SubmitForSegmentation(std::uint64_t frame_id, const cv::Mat& left,
                                       const TrackingResult& result) {
  // Synchronous pacing: every request is segmented and fused before the next one and before the next frame,
  // so that the labels fused, and the order they are summed in, never depend on the worker's speed.
  const bool synchronous = options_.pacing == Pacing::kSynchronous;
  auto submit = [&](std::uint64_t request, const cv::Mat& image, std::uint64_t frame) {
    segmentation_->Submit(request, image, static_cast<std::int64_t>(frame));
    if (synchronous) {
      ScopedTimer timer(timing_, "waiting_for_segmentation");
      segmentation_->WaitUntilIdle();
    }
  };
  recent_images_.emplace_back(frame_id, left);
  while (recent_images_.size() > kRecentImages) recent_images_.pop_front();
  if (!result.new_keyframes.empty()) {
    for (const NewKeyFrame& created : result.new_keyframes) {
      for (const auto& [id, image] : recent_images_) {
        if (id == created.frame_id) submit(created.keyframe_id, image, id);
      }
    }
    return;
  }
  // Keyframes come first; an idle worker also takes the other tracked frames (a fast segmenter then sees
  // every point many more times than the few keyframes that keep it). At synchronous pacing the worker is
  // always idle here: every tracked frame is segmented.
  const Frame* frame = tracker_->last_frame();
  if (result.state != TrackingState::kOk || frame == nullptr || segmentation_->Busy()) return;
  FrameObservations observations;
  for (size_t i = 0; i < frame->map_points.size(); ++i) {
    if (frame->map_points[i] == nullptr || frame->outliers[i]) continue;
    observations.points.push_back(frame->map_points[i]);
    observations.pixels.push_back(frame->features().keypoints[i].pixel);
  }
  if (observations.points.empty()) return;
  const std::uint64_t request = kFrameRequest | frame_id;
  {
    std::lock_guard pending(pending_frames_mutex_);
    pending_frames_[request] = std::move(observations);
  }
  submit(request, left, frame_id);
}

void SlamSystem::DiscardActiveMap() {
  ++resets_;
  mapper_->RequestStop();
  while (!mapper_->IsStopped() && !mapper_->IsFinished())
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  loop_closer_->WaitUntilIdle();
  {
    auto lock = map_->WriteLock();
    mapper_->Reset();
    loop_closer_->Reset();
    const std::uint32_t discarded = map_->active_map_id();
    for (const KeyFrame* kf : map_->KeyFramesOfMap(discarded)) database_->Erase(kf->id());
    map_->DiscardMap(discarded);
    map_->StartNewMap();
  }
  tracker_->Reset();
  mapper_->Release();
}

void SlamSystem::Finish() {
  if (finished_) return;
  finished_ = true;
  if (!options_.localization_only) {
    mapper_->WaitUntilIdle();
    loop_closer_->WaitUntilIdle();
    mapper_->WaitUntilIdle();
  }
  loop_closer_->RequestFinish();
  loop_closer_->Join();
  mapper_->RequestFinish();
  mapper_->Join();
  // The keyframe being segmented (and the newest pending one) still count.
  if (segmentation_) segmentation_->Stop(/*drain=*/true);
  if (options_.final_global_ba && !options_.localization_only) {
    ScopedTimer timer(timing_, "final_global_ba");
    auto lock = map_->WriteLock();
    const bool refine = options_.final_refine_intrinsics && options_.mode == SensorMode::kMonocular;
    GlobalBundleAdjustmentOptions global_ba;
    global_ba.iterations = options_.final_global_ba_iterations;
    global_ba.refine_iterations = options_.final_global_ba_refine_iterations;
    global_ba.window_keyframes = options_.loop.global_ba_window_keyframes;
    global_ba.follow_local_scale = options_.mode == SensorMode::kMonocular;
    SelfCalibrationOptions calibration;
    calibration.min_cost_reduction = options_.final_refine_intrinsics_min_reduction;
    calibration.min_keyframes = options_.final_refine_intrinsics_min_keyframes;
    for (const std::uint32_t map_id : map_->MapIds()) {
      if (map_->NumKeyFramesOfMap(map_id) <= 2) continue;
      const auto known = map_cameras_.find(map_id);
      const MapCamera map_camera = known != map_cameras_.end() ? known->second : SessionCamera();
      if (refine && !map_camera.camera.distortion.IsZero()) {
        // The refinement's radial terms act on the keypoints as the keyframes hold them, undistorted already:
        // kept, they would make a camera no PinholeCamera is, and the map could not record it.
        GlobalBundleAdjustment(*map_, map_id, global_ba);
        IntrinsicsRefinement& r = intrinsics_refinements_.emplace_back();
        r.map_id = map_id;
        r.nominal = r.refined = map_camera.camera;
        r.reason = map_camera.refined()
                       ? "the map was tracked with the refined camera of an earlier session, which it keeps"
                       : "the camera has lens distortion: a refinement's radial terms cannot be added to it";
        spdlog::info("map {}: the intrinsics stay as given: {}", map_id, r.reason);
      } else if (refine) {
        const IntrinsicsRefinement& r = intrinsics_refinements_.emplace_back(
            SelfCalibratingGlobalBundleAdjustment(*map_, map_id, global_ba, calibration));
        if (r.accepted) {
          // The keyframes' camera was the raw one (no distortion): the refined camera undistorts raw pixels.
          map_cameras_[map_id] = {map_camera.nominal, r.refined};
          spdlog::info(
              "map {}: the final bundle adjustment refined the intrinsics, which become the map's camera: "
              "f {:.1f} -> {:.1f}, principal point ({:.1f}, {:.1f}) -> ({:.1f}, {:.1f}), k1 {:.4f}, k2 "
              "{:.4f}; "
              "cost {:.0f} -> {:.0f}",
              map_id, r.nominal.fx, r.refined.fx, r.nominal.cx, r.nominal.cy, r.refined.cx, r.refined.cy,
              r.refined.distortion.k1, r.refined.distortion.k2, r.plain_cost, r.refined_cost);
        } else {
          spdlog::info("map {}: the intrinsics stay as given: {} (f {:.1f} -> {:.1f}, cost {:.0f} -> {:.0f})",
                       map_id, r.reason, r.nominal.fx, r.refined.fx, r.plain_cost, r.refined_cost);
        }
      } else {
        GlobalBundleAdjustment(*map_, map_id, global_ba);
      }
    }
  }
}

}  // namespace semslam
