#include "semslam/loop/loop_closer.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>
#include <unordered_map>

#include "semslam/core/error.h"
#include "semslam/geometry/sim3_solver.h"
#include "semslam/map/keyframe_graph.h"
#include "semslam/map/keyframe_matches.h"
#include "semslam/map/map_matcher.h"
#include "semslam/map/place_candidates.h"
#include "semslam/mapping/local_mapper.h"
#include "semslam/mapping/map_optimization.h"
#include "semslam/mapping/sim3_refinement.h"
#include "semslam/optim/bundle_adjustment.h"
#include "semslam/optim/pose_graph.h"
#include "semslam/optim/sim3_optimization.h"
#include "semslam/place/keyframe_database.h"
#include "semslam/place/vocabulary.h"

namespace semslam {

void LoopCloserOptions::Check() const {
  Require(consistency_threshold >= 1, "loop closer: consistency_threshold must be >= 1");
  Require(min_keyframes_between_loops >= 0, "loop closer: min_keyframes_between_loops must be >= 0");
  Require(min_bow_matches >= 3 && min_sim3_inliers >= 3 && min_projected_matches >= 3,
          "loop closer: match thresholds must be >= 3");
  Require(global_ba_iterations > 0, "loop closer: global_ba_iterations must be positive");
  Require(global_ba_window_keyframes >= 2, "loop closer: global_ba_window_keyframes must be >= 2");
  Require(min_verified_neighbours >= 0 && min_verified_neighbours <= 5 && verification_matches >= 3,
          "loop closer: min_verified_neighbours must be in [0, 5] and verification_matches >= 3");
  Require(max_depth_ratio > 1.0, "loop closer: max_depth_ratio must be > 1");
  Require(max_refined_depth_ratio > 1.0 && max_refined_depth_ratio <= max_depth_ratio,
          "loop closer: max_refined_depth_ratio must be in (1, max_depth_ratio]");
  Require(max_stereo_correction_ratio > 0 && stereo_correction_slack_m >= 0 &&
              max_mono_correction_ratio > 0 && mono_correction_slack_depths >= 0,
          "loop closer: max_stereo_correction_ratio and max_mono_correction_ratio must be positive, "
          "stereo_correction_slack_m and mono_correction_slack_depths >= 0");
  Require(stereo_rotation_slack_deg >= 0 && max_stereo_rotation_deg_per_100m >= 0 &&
              max_mono_loop_rotation_deg > 0 && max_mono_loop_rotation_deg <= 180,
          "loop closer: stereo_rotation_slack_deg and max_stereo_rotation_deg_per_100m must be >= 0, "
          "max_mono_loop_rotation_deg in (0, 180]");
}

Rigid3d RigidPose(const Sim3d& camera_from_world) {
  return Rigid3d(camera_from_world.rotation, camera_from_world.translation / camera_from_world.scale);
}

LoopCorrectionSize MeasureCorrection(const Rigid3d& before, const Sim3d& after) {
  const Rigid3d corrected = RigidPose(after);
  return {(corrected.Inverse().translation - before.Inverse().translation).norm(),
          (corrected * before.Inverse()).RotationAngle() * 180.0 / std::numbers::pi, after.scale};
}

double LoopCloserOptions::MaxStereoCorrectionM(double odometry_m) const {
  return max_stereo_correction_ratio * odometry_m + stereo_correction_slack_m;
}

double LoopCloserOptions::MaxMonoCorrection(double odometry, double loop_scale, double scene_depth) const {
  const double scale_drift = std::max(loop_scale, 1.0 / loop_scale) - 1.0;
  return (max_mono_correction_ratio + scale_drift) * odometry + mono_correction_slack_depths * scene_depth;
}

double LoopCloserOptions::MaxCorrection(double odometry, double loop_scale, double scene_depth) const {
  return fix_scale ? MaxStereoCorrectionM(odometry) : MaxMonoCorrection(odometry, loop_scale, scene_depth);
}

double LoopCloserOptions::MaxRotationDeg(double odometry_m) const {
  if (!fix_scale) return max_mono_loop_rotation_deg;
  return stereo_rotation_slack_deg + max_stereo_rotation_deg_per_100m * odometry_m / 100.0;
}

bool LoopCloserOptions::AllowsCorrection(const LoopCorrectionSize& correction, double odometry_m,
                                         double scene_depth) const {
  return correction.degrees <= MaxRotationDeg(odometry_m) &&
         correction.metres <= MaxCorrection(odometry_m, correction.scale, scene_depth);
}

LoopCloser::LoopCloser(const LoopCloserOptions& options, Map& map, const Vocabulary& vocabulary,
                       KeyFrameDatabase& database, LocalMapper& mapper, TimingRegistry& timing)
    : options_(options),
      map_(map),
      vocabulary_(vocabulary),
      database_(database),
      mapper_(mapper),
      timing_(timing) {
  options_.Check();
}

LoopCloser::~LoopCloser() {
  RequestFinish();
  Join();
}

void LoopCloser::Start() {
  if (thread_.joinable()) return;
  finish_requested_ = false;
  thread_ = std::thread([this] { Run(); });
}

void LoopCloser::RequestFinish() {
  finish_requested_ = true;
  queue_cv_.notify_all();
}

void LoopCloser::Join() {
  if (thread_.joinable()) thread_.join();
  if (global_ba_thread_.joinable()) global_ba_thread_.join();
}

void LoopCloser::InsertKeyFrame(KeyFrame* keyframe) {
  if (!options_.enabled || keyframe->is_map_origin()) return;
  {
    std::lock_guard lock(queue_mutex_);
    queue_.push_back(keyframe);
  }
  queue_cv_.notify_all();
}

void LoopCloser::WaitUntilIdle() {
  {
    std::unique_lock lock(queue_mutex_);
    queue_cv_.wait(lock, [this] { return (queue_.empty() && !busy_) || !thread_.joinable(); });
  }
  if (global_ba_thread_.joinable()) global_ba_thread_.join();
}

void LoopCloser::Reset() {
  std::lock_guard lock(queue_mutex_);
  queue_.clear();
  consistent_groups_.clear();
  enough_consistent_candidates_.clear();
  last_loop_keyframe_id_ = 0;
}

void LoopCloser::ForgetCandidates() {
  consistent_groups_.clear();
  enough_consistent_candidates_.clear();
}

std::vector<LoopEvent> LoopCloser::loops() const {
  std::lock_guard lock(loops_mutex_);
  std::vector<LoopEvent> out;
  for (const LoopEvent& e : events_) {
    if (!e.merge) out.push_back(e);
  }
  return out;
}

std::vector<LoopEvent> LoopCloser::merges() const {
  std::lock_guard lock(loops_mutex_);
  std::vector<LoopEvent> out;
  for (const LoopEvent& e : events_) {
    if (e.merge) out.push_back(e);
  }
  return out;
}

void LoopCloser::Run() {
  while (true) {
    KeyFrame* current = nullptr;
    {
      std::unique_lock lock(queue_mutex_);
      queue_cv_.wait(lock, [this] { return !queue_.empty() || finish_requested_.load(); });
      if (queue_.empty()) break;
      current = queue_.front();
      queue_.pop_front();
      busy_ = true;
    }
    ProcessKeyFrame(current, {}, place_check_);
    {
      std::lock_guard lock(queue_mutex_);
      busy_ = false;
    }
    queue_cv_.notify_all();
  }
  std::lock_guard lock(queue_mutex_);
  busy_ = false;
  queue_cv_.notify_all();
}

bool LoopCloser::ProcessKeyFrame(KeyFrame* current, const PlaceExclusions& excluded,
                                 const PlaceCheck& place_check) {
  Stopwatch watch;
  bool corrected = false;
  if (DetectLoop(current, excluded)) {
    const auto checked = [&] {
      if (!place_check || (matched_keyframe_->map_id() == current->map_id() &&
                           matched_keyframe_->session() == current->session()))
        return true;
      auto lock = map_.ReadLock();
      return place_check(*current, *matched_keyframe_,
                         current_from_world_.Inverse() * Sim3d(current->camera_from_world()));
    };
    if (ComputeSim3(current) && checked()) {
      CorrectLoop(current);
      corrected = true;
    } else {
      auto lock = map_.WriteLock();
      for (KeyFrame* kf : enough_consistent_candidates_) kf->SetErase();
      current->SetErase();
    }
  }
  timing_.Add("loop_closing", watch.ElapsedMs());
  return corrected;
}

bool LoopCloser::DetectLoop(KeyFrame* current, const PlaceExclusions& excluded) {
  ScopedTimer timer(timing_, "loop_detection");
  auto lock = map_.ReadLock();
  if (current->is_bad()) return false;
  {
    // Protect the keyframe from culling while it is being examined.
    lock.unlock();
    auto write = map_.WriteLock();
    current->SetNotErase();
  }
  lock.lock();
  auto release = [&] {
    lock.unlock();
    auto write = map_.WriteLock();
    current->SetErase();
    return false;
  };
  if (current->id() <
      last_loop_keyframe_id_ + static_cast<std::uint64_t>(options_.min_keyframes_between_loops)) {
    return release();
  }
  // The lowest similarity to the covisible keyframes sets the bar for loop candidates.
  const std::vector<KeyFrame*> covisibles = current->Covisibles();
  double min_score = 1.0;
  for (KeyFrame* kf : covisibles) {
    if (kf->is_bad() || !kf->has_bow) continue;
    min_score = std::min(min_score, vocabulary_.Score(current->bow, kf->bow));
  }
  PlaceCandidateOptions candidate_options;
  candidate_options.min_score = min_score;
  candidate_options.excluded = {current->id()};
  for (KeyFrame* kf : covisibles) candidate_options.excluded.insert(kf->id());
  if (!options_.merge_maps) candidate_options.map_id = current->map_id();
  candidate_options.excluded_maps = excluded.maps;
  candidate_options.excluded_sessions = excluded.sessions;
  const std::vector<KeyFrame*> candidates =
      FindPlaceCandidates(current->bow, database_, map_, candidate_options);
  if (candidates.empty()) {
    consistent_groups_.clear();
    return release();
  }

  // Covisibility consistency: a candidate's group must overlap a group found for previous keyframes.
  enough_consistent_candidates_.clear();
  std::vector<ConsistentGroup> current_groups;
  std::vector<bool> previous_extended(consistent_groups_.size(), false);
  for (KeyFrame* candidate : candidates) {
    ConsistentGroup group;
    group.keyframes.insert(candidate);
    for (KeyFrame* kf : candidate->Covisibles()) group.keyframes.insert(kf);
    bool consistent_for_some = false;
    bool enough = false;
    for (size_t g = 0; g < consistent_groups_.size(); ++g) {
      const bool overlaps = std::any_of(group.keyframes.begin(), group.keyframes.end(), [&](KeyFrame* kf) {
        return consistent_groups_[g].keyframes.count(kf) > 0;
      });
      if (!overlaps) continue;
      consistent_for_some = true;
      const int consistency = consistent_groups_[g].consistency + 1;
      if (!previous_extended[g]) {
        current_groups.push_back({group.keyframes, consistency});
        previous_extended[g] = true;
      }
      if (consistency >= options_.consistency_threshold && !enough) {
        enough_consistent_candidates_.push_back(candidate);
        enough = true;
      }
    }
    if (!consistent_for_some) current_groups.push_back({group.keyframes, 0});
  }
  consistent_groups_ = std::move(current_groups);
  if (enough_consistent_candidates_.empty()) return release();
  lock.unlock();
  auto write = map_.WriteLock();
  for (KeyFrame* kf : enough_consistent_candidates_) kf->SetNotErase();
  return true;
}

bool LoopCloser::ComputeSim3(KeyFrame* current) {
  ScopedTimer timer(timing_, "loop_sim3");
  auto lock = map_.ReadLock();
  matched_keyframe_ = nullptr;
  for (KeyFrame* candidate : enough_consistent_candidates_) {
    if (candidate->is_bad()) continue;
    std::vector<MapPoint*> matches;
    if (SearchByBow(*current, *candidate, matches, 0.75f) < options_.min_bow_matches) continue;

    const std::vector<KeyFramePointMatch> usable = MatchesInCameraFrames(*current, *candidate, matches);
    Sim3Correspondences correspondences;
    correspondences.camera1 = current->camera();
    correspondences.camera2 = candidate->camera();
    for (const KeyFramePointMatch& m : usable) {
      const Keypoint& kp1 = current->features().keypoints[m.slot1];
      const Keypoint& kp2 = candidate->features().keypoints[m.slot2];
      correspondences.points1.push_back(m.point1);
      correspondences.points2.push_back(m.point2);
      correspondences.pixels1.push_back(kp1.pixel.cast<double>());
      correspondences.pixels2.push_back(kp2.pixel.cast<double>());
      correspondences.sigma2_1.push_back(current->features().pyramid.sigma2[kp1.level]);
      correspondences.sigma2_2.push_back(candidate->features().pyramid.sigma2[kp2.level]);
    }
    Sim3RansacOptions ransac;
    ransac.fix_scale = options_.fix_scale;
    ransac.min_inliers = options_.min_sim3_inliers;
    ransac.max_iterations = 300;
    ransac.seed = current->id() * 7919 + candidate->id();
    const auto solution = EstimateSim3Ransac(correspondences, ransac);
    if (!solution) continue;

    // Guided matching with the estimate, then refinement by reprojection in both keyframes.
    std::vector<MapPoint*> guided(current->num_features(), nullptr);
    for (size_t k = 0; k < usable.size(); ++k) {
      if (solution->inliers[k]) guided[usable[k].slot1] = matches[usable[k].slot1];
    }
    SearchBySim3(*current, *candidate, guided, solution->camera1_from_camera2, 7.5f);
    Sim3d current_from_candidate = solution->camera1_from_camera2;
    const int inliers = RefineLoopSim3(*current, *candidate, guided, &current_from_candidate);
    if (inliers < options_.min_sim3_inliers) continue;
    if (!AgreesWithStructure(*current, *candidate, guided, current_from_candidate)) continue;

    matched_keyframe_ = candidate;
    current_from_world_ = current_from_candidate * Sim3d(candidate->camera_from_world());
    // Points around the matched place, projected into the current keyframe for more matches.
    loop_points_.clear();
    std::set<MapPoint*> unique;
    std::vector<KeyFrame*> around = candidate->Covisibles();
    around.push_back(candidate);
    for (KeyFrame* kf : around) {
      for (MapPoint* p : kf->map_points()) {
        if (p != nullptr && !p->is_bad() && unique.insert(p).second) loop_points_.push_back(p);
      }
    }
    current_matched_points_ = guided;
    SearchBySim3Projection(*current, current_from_world_, loop_points_, current_matched_points_, 10);
    last_matches_ =
        static_cast<int>(std::count_if(current_matched_points_.begin(), current_matched_points_.end(),
                                       [](MapPoint* p) { return p != nullptr; }));
    if (last_matches_ < options_.min_projected_matches) continue;
    last_verified_ = CountVerifiedNeighbours(current);
    if (last_verified_ < options_.min_verified_neighbours) {
      spdlog::info(
          "loop candidate: keyframe {} with keyframe {} ({} matches) not confirmed by its neighbours "
          "({} of {} needed)",
          current->id(), candidate->id(), last_matches_, last_verified_, options_.min_verified_neighbours);
      continue;
    }
    if (!CorrectionAgreesWithOdometry(current, candidate)) continue;
    {
      lock.unlock();
      auto write = map_.WriteLock();
      for (KeyFrame* kf : enough_consistent_candidates_) {
        if (kf != candidate) kf->SetErase();
      }
      return true;
    }
  }
  return false;
}

int LoopCloser::RefineLoopSim3(const KeyFrame& current, const KeyFrame& candidate,
                               std::vector<MapPoint*>& matches, Sim3d* current_from_candidate) const {
  constexpr double kChi2 = 10.0;
  if (options_.fix_scale) return RefineSim3(current, candidate, matches, current_from_candidate, kChi2, true);
  const MonocularSim3Refinement refined = RefineSim3KeepingStructureScale(
      current, candidate, matches, current_from_candidate, kChi2, options_.max_refined_depth_ratio);
  if (refined.scale_held) {
    spdlog::info(
        "loop candidate: keyframe {} with keyframe {}: the refinement's scale {:.3f} put the matched "
        "points at {:.2f} times their own depth; refined again at the structures' scale {:.3f}",
        current.id(), candidate.id(), refined.free_scale, 1.0 / refined.free_depth_ratio,
        current_from_candidate->scale);
  }
  return refined.inliers;
}

bool LoopCloser::AgreesWithStructure(const KeyFrame& current, const KeyFrame& candidate,
                                     const std::vector<MapPoint*>& matches,
                                     const Sim3d& current_from_candidate) const {
  const std::optional<double> structure_ratio =
      StructureDepthRatio(current, candidate, matches, current_from_candidate);
  if (!structure_ratio) return false;
  const double ratio = *structure_ratio;
  const bool agrees = DepthRatioWithin(ratio, options_.max_depth_ratio);
  spdlog::info(
      "loop candidate: keyframe {} with keyframe {}: its transform (scale {:.3f}) puts the matched points at "
      "{:.2f} "
      "times their own depth (limit {:.2f}){}",
      current.id(), candidate.id(), current_from_candidate.scale, 1.0 / ratio, options_.max_depth_ratio,
      agrees ? "" : "; refused");
  return agrees;
}

bool LoopCloser::CorrectionAgreesWithOdometry(const KeyFrame* current, const KeyFrame* candidate) const {
  if (candidate->map_id() != current->map_id()) return true;  // maps to merge share no odometry
  const LoopCorrectionSize correction = MeasureCorrection(current->camera_from_world(), current_from_world_);
  // The odometry between the two ends (metres in a stereo map, its units in a monocular one): the shortest
  // chain of the links the essential graph holds, so a revisit tracked in the map, an earlier loop or a
  // merge shortens it. Counting the path driven instead let a look-alike 24 m away pass at the third visit
  // of a place (900 m driven, 30 m allowed).
  constexpr int kEssentialCovisibility = 100;  // as in OptimizeEssentialGraph
  const double odometry = KeyFrameGraphDistance(*candidate, *current, kEssentialCovisibility);
  const double scene_depth = current->SceneDepthQuantile(2);
  const bool agrees = options_.AllowsCorrection(correction, odometry, scene_depth);
  const double max_move = options_.MaxCorrection(odometry, correction.scale, scene_depth);
  const char* unit = options_.fix_scale ? " m" : "";
  spdlog::info(
      "loop candidate: keyframe {} with keyframe {} {} the keyframe {:.2f}{} and {:.1f} deg "
      "after {:.2f}{} of odometry between them, its scene {:.2f}{} deep (limits {:.2f}{}, {:.1f} deg){}",
      current->id(), candidate->id(), agrees ? "moves" : "refused: it would move", correction.metres, unit,
      correction.degrees, odometry, unit, scene_depth, unit, max_move, unit,
      options_.MaxRotationDeg(odometry), agrees ? "" : "; a place that only looks the same");
  return agrees;
}

int LoopCloser::CountVerifiedNeighbours(const KeyFrame* current) const {
  const Rigid3d world_from_current = current->world_from_camera();
  int verified = 0;
  for (KeyFrame* neighbour : current->BestCovisibles(5)) {
    if (neighbour->is_bad()) continue;
    // Where the loop puts the neighbour: its pose relative to the current keyframe, after the correction.
    const Sim3d corrected = Sim3d(neighbour->camera_from_world() * world_from_current) * current_from_world_;
    std::vector<MapPoint*> matched(neighbour->num_features(), nullptr);
    const int found = SearchBySim3Projection(*neighbour, corrected, loop_points_, matched, 10);
    if (found >= options_.verification_matches) ++verified;
  }
  return verified;
}

}  // namespace semslam
