#include "semslam/system/slam_system.h"

#include <chrono>
#include <thread>

#include <spdlog/spdlog.h>

#include "semslam/core/error.h"
#include "semslam/mapping/map_optimization.h"
#include "semslam/place/keyframe_database.h"
#include "semslam/place/vocabulary.h"

namespace semslam {

void SlamOptions::Check() const {
  tracker.Check();
  mapper.Check();
  loop.Check();
  Require(tracker.monocular == (mode == SensorMode::kMonocular), "slam: tracker mode disagrees with the sensor mode");
}

SlamSystem::SlamSystem(const SlamOptions& options, const PinholeCamera& camera, std::optional<StereoRig> stereo)
    : options_(options), camera_(camera), stereo_(std::move(stereo)) {
  options_.tracker.monocular = options_.mode == SensorMode::kMonocular;
  options_.mapper.monocular = options_.tracker.monocular;
  options_.loop.fix_scale = !options_.tracker.monocular;
  if (!options_.tracker.monocular) options_.loop.max_correction_ratio = std::min(options_.loop.max_correction_ratio, 0.1);
  options_.tracker.localization_only = options_.localization_only;
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
  loop_closer_ = std::make_unique<LoopCloser>(options_.loop, *map_, *vocabulary_, *database_, *mapper_, timing_);
  mapper_->AddKeyFrameListener([this](KeyFrame* kf) { loop_closer_->InsertKeyFrame(kf); });
  tracker_ = std::make_unique<Tracker>(options_.tracker, camera_, stereo_, *map_, *vocabulary_, *database_,
                                       options_.localization_only ? nullptr : mapper_.get(), timing_);
  if (!options_.localization_only) {
    mapper_->Start();
    loop_closer_->Start();
  }
}

SlamSystem::~SlamSystem() { Finish(); }

MapFileContents SlamSystem::LoadMap(const std::filesystem::path& path) {
  Require(frames_ == 0, "a map can only be loaded before the first frame");
  auto lock = map_->WriteLock();
  MapFileContents contents = ReadMapFile(path, *map_);
  for (KeyFrame* kf : map_->KeyFrames()) {
    vocabulary_->Transform(kf->features().descriptors, &kf->bow, &kf->feature_vector);
    kf->has_bow = true;
    database_->Add(kf->id(), kf->bow);
  }
  spdlog::info("map {} loaded: {} keyframes, {} points", path.string(), map_->NumKeyFrames(), map_->NumMapPoints());
  tracker_->SetMapLoaded();
  return contents;
}

void SlamSystem::SaveMap(const std::filesystem::path& path, const MapFileContents& extra) const {
  auto lock = map_->ReadLock();
  WriteMapFile(path, *map_, extra);
}

TrackingResult SlamSystem::ProcessFrame(std::uint64_t frame_id, double timestamp, const cv::Mat& left,
                                        const cv::Mat& right, const cv::Mat& mask) {
  Require(!finished_, "ProcessFrame after Finish");
  if (options_.pacing == Pacing::kRealtime) {
    // Feed frames no faster than the camera recorded them.
    if (!clock_) {
      clock_.emplace();
      first_timestamp_ = timestamp;
    }
    const double due_ms = (timestamp - first_timestamp_) * 1000.0;
    const double wait_ms = due_ms - clock_->ElapsedMs();
    if (wait_ms > 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(wait_ms));
  }
  TrackingResult result = tracker_->Track(frame_id, timestamp, left, right, mask);
  ++frames_;
  if (result.state == TrackingState::kOk) ++tracked_;
  if (result.reset_requested) ResetMap();
  if (options_.pacing == Pacing::kSynchronous && (result.new_keyframe || result.initialized_now)) {
    mapper_->WaitUntilIdle();
  }
  return result;
}

void SlamSystem::ResetMap() {
  ++resets_;
  mapper_->RequestStop();
  while (!mapper_->IsStopped() && !mapper_->IsFinished()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  loop_closer_->WaitUntilIdle();
  {
    auto lock = map_->WriteLock();
    mapper_->Reset();
    loop_closer_->Reset();
    database_->Clear();
    map_->Clear();
  }
  const auto& records = tracker_->records();
  old_records_.insert(old_records_.end(), records.begin(), records.end());
  for (auto& record : old_records_) record.reference = nullptr;  // that map is gone
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
  if (options_.final_global_ba && !options_.localization_only) {
    ScopedTimer timer(timing_, "final_global_ba");
    auto lock = map_->WriteLock();
    if (map_->NumKeyFrames() > 2) GlobalBundleAdjustment(*map_, options_.final_global_ba_iterations, nullptr);
  }
}

Trajectory SlamSystem::FrameTrajectory() const {
  auto lock = map_->ReadLock();
  Trajectory trajectory;
  for (const FrameRecord& record : tracker_->records()) {
    if (record.reference == nullptr) continue;
    // A culled reference keyframe hands its frames to its parent through the stored relative pose.
    KeyFrame* kf = record.reference;
    Rigid3d camera_from_kf = record.camera_from_reference;
    while (kf->is_bad() && kf->parent() != nullptr) {
      camera_from_kf = camera_from_kf * kf->camera_from_parent();
      kf = kf->parent();
    }
    if (kf->is_bad()) continue;
    const Rigid3d camera_from_world = camera_from_kf * kf->camera_from_world();
    trajectory.push_back({record.timestamp, camera_from_world.Inverse()});
  }
  return trajectory;
}

Trajectory SlamSystem::KeyFrameTrajectory() const {
  auto lock = map_->ReadLock();
  Trajectory trajectory;
  for (const KeyFrame* kf : map_->KeyFrames()) {
    if (!kf->is_bad()) trajectory.push_back({kf->timestamp(), kf->world_from_camera()});
  }
  return trajectory;
}

SlamStatistics SlamSystem::Statistics() const {
  SlamStatistics s;
  s.frames = frames_;
  s.tracked = tracked_;
  s.relocalizations = static_cast<size_t>(tracker_->num_relocalizations());
  s.loops = loop_closer_->loops().size();
  s.resets = resets_;
  auto lock = map_->ReadLock();
  s.keyframes = map_->NumKeyFrames();
  for (const MapPoint* p : map_->MapPoints()) s.map_points += p->is_bad() ? 0 : 1;
  return s;
}

std::vector<LoopEvent> SlamSystem::Loops() const { return loop_closer_->loops(); }

}  // namespace semslam
