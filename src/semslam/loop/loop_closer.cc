#include "semslam/loop/loop_closer.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <unordered_map>

#include "semslam/core/error.h"
#include "semslam/geometry/sim3_solver.h"
#include "semslam/map/map_matcher.h"
#include "semslam/map/place_candidates.h"
#include "semslam/mapping/local_mapper.h"
#include "semslam/mapping/map_optimization.h"
#include "semslam/optim/bundle_adjustment.h"
#include "semslam/optim/pose_graph.h"
#include "semslam/optim/sim3_optimization.h"
#include "semslam/place/keyframe_database.h"
#include "semslam/place/vocabulary.h"

namespace semslam {
namespace {

Sim3d ToSim3(const Rigid3d& t) { return Sim3d(t); }
// The rigid pose of a similarity camera_from_world: rotation kept, translation divided by the scale.
Rigid3d ToRigid(const Sim3d& s) { return Rigid3d(s.rotation, s.translation / s.scale); }

}  // namespace

void LoopCloserOptions::Check() const {
  Require(consistency_threshold >= 1, "loop closer: consistency_threshold must be >= 1");
  Require(min_keyframes_between_loops >= 0, "loop closer: min_keyframes_between_loops must be >= 0");
  Require(min_bow_matches >= 3 && min_sim3_inliers >= 3 && min_projected_matches >= 3,
          "loop closer: match thresholds must be >= 3");
  Require(global_ba_iterations > 0, "loop closer: global_ba_iterations must be positive");
  Require(min_verified_neighbours >= 0 && min_verified_neighbours <= 5 && verification_matches >= 3,
          "loop closer: min_verified_neighbours must be in [0, 5] and verification_matches >= 3");
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
    Stopwatch watch;
    if (DetectLoop(current)) {
      if (ComputeSim3(current)) {
        CorrectLoop(current);
      } else {
        auto lock = map_.WriteLock();
        for (KeyFrame* kf : enough_consistent_candidates_) kf->SetErase();
        current->SetErase();
      }
    }
    timing_.Add("loop_closing", watch.ElapsedMs());
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

bool LoopCloser::DetectLoop(KeyFrame* current) {
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

    Sim3Correspondences correspondences;
    correspondences.camera1 = current->camera();
    correspondences.camera2 = candidate->camera();
    std::vector<int> slots;
    for (size_t i = 0; i < matches.size(); ++i) {
      MapPoint* p1 = current->map_point(static_cast<int>(i));
      MapPoint* p2 = matches[i];
      if (p1 == nullptr || p2 == nullptr || p1->is_bad() || p2->is_bad()) continue;
      const int i2 = p2->IndexIn(candidate);
      if (i2 < 0) continue;
      const Keypoint& kp1 = current->features().keypoints[i];
      const Keypoint& kp2 = candidate->features().keypoints[static_cast<size_t>(i2)];
      correspondences.points1.push_back(current->camera_from_world() * p1->position());
      correspondences.points2.push_back(candidate->camera_from_world() * p2->position());
      correspondences.pixels1.push_back(kp1.pixel.cast<double>());
      correspondences.pixels2.push_back(kp2.pixel.cast<double>());
      correspondences.sigma2_1.push_back(current->features().pyramid.sigma2[kp1.level]);
      correspondences.sigma2_2.push_back(candidate->features().pyramid.sigma2[kp2.level]);
      slots.push_back(static_cast<int>(i));
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
    for (size_t k = 0; k < slots.size(); ++k) {
      if (solution->inliers[k])
        guided[static_cast<size_t>(slots[k])] = matches[static_cast<size_t>(slots[k])];
    }
    SearchBySim3(*current, *candidate, guided, solution->camera1_from_camera2, 7.5f);
    Sim3d current_from_candidate = solution->camera1_from_camera2;
    const int inliers =
        RefineSim3(*current, *candidate, guided, &current_from_candidate, 10.0, options_.fix_scale);
    if (inliers < options_.min_sim3_inliers) continue;

    matched_keyframe_ = candidate;
    current_from_world_ = current_from_candidate * ToSim3(candidate->camera_from_world());
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

int LoopCloser::CountVerifiedNeighbours(const KeyFrame* current) const {
  const Rigid3d world_from_current = current->world_from_camera();
  int verified = 0;
  for (KeyFrame* neighbour : current->BestCovisibles(5)) {
    if (neighbour->is_bad()) continue;
    // Where the loop puts the neighbour: its pose relative to the current keyframe, after the correction.
    const Sim3d corrected = ToSim3(neighbour->camera_from_world() * world_from_current) * current_from_world_;
    std::vector<MapPoint*> matched(neighbour->num_features(), nullptr);
    const int found = SearchBySim3Projection(*neighbour, corrected, loop_points_, matched, 10);
    if (found >= options_.verification_matches) ++verified;
  }
  return verified;
}

double LoopCloser::MoveMapToMatchedFrame(KeyFrame* current) {
  // current_from_world_ is the current keyframe's pose in the matched map's frame: the same transform takes
  // every pose and point of its map there (with the scale between the two, monocular).
  const std::uint32_t from = current->map_id(), into = matched_keyframe_->map_id();
  const Sim3d into_from_current_map = current_from_world_.Inverse() * ToSim3(current->camera_from_world());
  const Sim3d current_map_from_into = into_from_current_map.Inverse();
  for (MapPoint* p : map_.MapPointsOfMap(from)) {
    p->SetPosition(into_from_current_map * p->position());
    p->UpdateNormalAndDepth();
  }
  for (KeyFrame* kf : map_.KeyFramesOfMap(from)) {
    kf->SetPose(ToRigid(ToSim3(kf->camera_from_world()) * current_map_from_into));
  }
  map_.MergeMapInto(from, into);
  spdlog::info("map {} moved into the frame of map {} (scale {:.3f}) and merged", from, into,
               into_from_current_map.scale);
  return into_from_current_map.scale;
}

void LoopCloser::CorrectLoop(KeyFrame* current) {
  ScopedTimer timer(timing_, "loop_correction");
  const bool merge = matched_keyframe_->map_id() != current->map_id();
  spdlog::info(
      "{} detected: keyframe {} (map {}) matches keyframe {} (map {}), {} matches, confirmed by {} "
      "neighbours",
      merge ? "map merge" : "loop", current->id(), current->map_id(), matched_keyframe_->id(),
      matched_keyframe_->map_id(), last_matches_, last_verified_);
  mapper_.RequestStop();
  StopGlobalBundleAdjustment();
  while (!mapper_.IsStopped() && !mapper_.IsFinished())
    std::this_thread::sleep_for(std::chrono::milliseconds(1));

  LoopEvent event;
  event.query_keyframe = current->id();
  event.matched_keyframe = matched_keyframe_->id();
  event.query_timestamp = current->timestamp();
  event.matches = last_matches_;
  event.verified_neighbours = last_verified_;
  event.scale = current_from_world_.scale;
  event.merge = merge;
  event.map_id = current->map_id();
  event.matched_map_id = matched_keyframe_->map_id();

  std::map<KeyFrame*, std::set<KeyFrame*>> loop_connections;
  std::map<KeyFrame*, Sim3d> corrected, non_corrected;
  {
    auto lock = map_.WriteLock();
    if (merge) event.scale = MoveMapToMatchedFrame(current);
    current->UpdateConnections();
    std::vector<KeyFrame*> connected = current->Covisibles();
    connected.push_back(current);
    const Rigid3d world_from_current = current->world_from_camera();
    event.correction_m = (ToRigid(current_from_world_).Inverse().translation - current->center()).norm();

    // Propagate the correction to the keyframes around the current one through their relative poses.
    corrected[current] = current_from_world_;
    for (KeyFrame* kf : connected) {
      const Sim3d original = ToSim3(kf->camera_from_world());
      non_corrected[kf] = original;
      if (kf != current) {
        const Sim3d kf_from_current = ToSim3(kf->camera_from_world() * world_from_current);
        corrected[kf] = kf_from_current * current_from_world_;
      }
    }
    // Move their points and poses.
    for (const auto& [kf, corrected_pose] : corrected) {
      const Sim3d world_from_corrected = corrected_pose.Inverse();
      const Sim3d& original = non_corrected[kf];
      for (MapPoint* p : kf->map_points()) {
        if (p == nullptr || p->is_bad() || p->corrected_by_keyframe == current->id()) continue;
        p->SetPosition(world_from_corrected * (original * p->position()));
        p->corrected_by_keyframe = current->id();
        p->corrected_reference = kf->id();
        p->UpdateNormalAndDepth();
      }
      kf->SetPose(ToRigid(corrected_pose));
      kf->UpdateConnections();
    }
    // Fuse the loop: matched points replace the current keyframe's duplicates.
    for (size_t i = 0; i < current_matched_points_.size(); ++i) {
      MapPoint* loop_point = current_matched_points_[i];
      if (loop_point == nullptr || loop_point->is_bad()) continue;
      MapPoint* existing = current->map_point(static_cast<int>(i));
      if (existing == loop_point) continue;
      if (existing != nullptr && !existing->is_bad()) {
        existing->ReplaceWith(loop_point);
        map_.EraseMapPoint(existing);
      } else if (!loop_point->IsObservedBy(current)) {
        loop_point->AddObservation(current, static_cast<int>(i));
        current->SetMapPoint(static_cast<int>(i), loop_point);
        loop_point->UpdateDescriptor();
      }
    }
    // Project the loop's points into every corrected keyframe and merge duplicates.
    for (const auto& [kf, corrected_pose] : corrected) {
      std::vector<MapPoint*> replace;
      FuseWithSim3(*kf, corrected_pose, loop_points_, 4.0f, replace);
      for (size_t j = 0; j < replace.size(); ++j) {
        if (replace[j] != nullptr && !replace[j]->is_bad() && !loop_points_[j]->is_bad()) {
          replace[j]->ReplaceWith(loop_points_[j]);
          map_.EraseMapPoint(replace[j]);
        }
      }
    }
    // The new links the loop created.
    for (KeyFrame* kf : connected) {
      const std::vector<KeyFrame*> before = kf->Covisibles();
      kf->UpdateConnections();
      std::set<KeyFrame*> links(kf->Covisibles().begin(), kf->Covisibles().end());
      for (KeyFrame* b : before) links.erase(b);
      for (KeyFrame* c : connected) links.erase(c);
      loop_connections[kf] = links;
    }
    OptimizeEssentialGraph(matched_keyframe_, current, non_corrected, corrected, loop_connections);
    map_.NotifyBigChange();
    matched_keyframe_->AddLoopEdge(current);
    current->AddLoopEdge(matched_keyframe_);
  }
  {
    std::lock_guard lock(loops_mutex_);
    events_.push_back(event);
  }
  if (options_.global_ba) {
    global_ba_abort_ = false;
    global_ba_running_ = true;
    const std::uint64_t id = current->id();
    const std::uint32_t map_id = current->map_id();
    global_ba_thread_ = std::thread([this, id, map_id] { RunGlobalBundleAdjustment(id, map_id); });
  }
  mapper_.Release();
  last_loop_keyframe_id_ = current->id();
}

void LoopCloser::OptimizeEssentialGraph(KeyFrame* loop_keyframe, KeyFrame* current,
                                        const std::map<KeyFrame*, Sim3d>& non_corrected,
                                        const std::map<KeyFrame*, Sim3d>& corrected,
                                        const std::map<KeyFrame*, std::set<KeyFrame*>>& loop_connections) {
  ScopedTimer timer(timing_, "essential_graph");
  constexpr int kMinWeight = 100;
  const std::vector<KeyFrame*> keyframes = map_.KeyFramesOfMap(current->map_id());
  PoseGraph graph;
  std::unordered_map<const KeyFrame*, int> node;
  std::unordered_map<const KeyFrame*, Sim3d> before;  // camera_from_world used for relative measurements
  for (KeyFrame* kf : keyframes) {
    if (kf->is_bad()) continue;
    const auto c = corrected.find(kf);
    const Sim3d camera_from_world = c != corrected.end() ? c->second : ToSim3(kf->camera_from_world());
    const auto nc = non_corrected.find(kf);
    before[kf] = nc != non_corrected.end() ? nc->second : ToSim3(kf->camera_from_world());
    node[kf] = graph.AddNode(camera_from_world.Inverse(), kf == loop_keyframe || kf->is_map_origin());
  }
  std::set<std::pair<int, int>> added;
  auto add_edge = [&](KeyFrame* a, KeyFrame* b, bool use_corrected) {
    const auto ia = node.find(a), ib = node.find(b);
    if (ia == node.end() || ib == node.end()) return;
    const auto key = std::minmax(ia->second, ib->second);
    if (!added.insert(key).second) return;
    // a_from_b measured from the poses before the correction (or after it, for the new loop links).
    Sim3d a_cw = before[a], b_cw = before[b];
    if (use_corrected) {
      const auto ca = corrected.find(a), cb = corrected.find(b);
      if (ca != corrected.end()) a_cw = ca->second;
      if (cb != corrected.end()) b_cw = cb->second;
    }
    graph.AddRelativeEdge(ia->second, ib->second, a_cw * b_cw.Inverse(), 1.0);
  };
  // Loop links first (measured with the corrected poses), then the spanning tree, loop edges and strong
  // covisibility.
  for (const auto& [kf, links] : loop_connections) {
    for (KeyFrame* other : links) {
      if ((kf == current || other == loop_keyframe) || kf->ConnectionWeight(other) >= kMinWeight) {
        add_edge(kf, other, true);
      }
    }
  }
  for (KeyFrame* kf : keyframes) {
    if (kf->is_bad()) continue;
    if (kf->parent() != nullptr) add_edge(kf, kf->parent(), false);
    for (KeyFrame* other : kf->loop_edges()) add_edge(kf, other, false);
    for (KeyFrame* other : kf->CovisiblesWithWeightAtLeast(kMinWeight)) add_edge(kf, other, false);
  }
  PoseGraphOptions options;
  options.fix_scale = options_.fix_scale;
  options.max_iterations = 20;
  graph.Optimize(options);

  // Poses from the graph; each point follows the keyframe that corrected it (or its reference).
  std::unordered_map<std::uint64_t, std::pair<Sim3d, Sim3d>> change;  // id -> (before cw, after wc)
  for (const auto& [kf, index] : node) {
    const Sim3d world_from_kf = graph.world_from_node(index);
    const Sim3d camera_from_world = world_from_kf.Inverse();
    change[kf->id()] = {before[kf], world_from_kf};
    const_cast<KeyFrame*>(kf)->SetPose(ToRigid(camera_from_world));
  }
  for (MapPoint* p : map_.MapPointsOfMap(current->map_id())) {
    if (p->is_bad()) continue;
    const std::uint64_t ref = p->corrected_by_keyframe == current->id()
                                  ? p->corrected_reference
                                  : (p->reference_keyframe() ? p->reference_keyframe()->id() : UINT64_MAX);
    const auto it = change.find(ref);
    if (it == change.end()) continue;
    // For corrected points, `before` of the reference is the corrected pose they were moved with.
    const auto c = corrected.find(map_.KeyFrameById(ref));
    const Sim3d& reference_cw =
        (p->corrected_by_keyframe == current->id() && c != corrected.end()) ? c->second : it->second.first;
    p->SetPosition(it->second.second * (reference_cw * p->position()));
    p->UpdateNormalAndDepth();
  }
}

void LoopCloser::StopGlobalBundleAdjustment() {
  if (!global_ba_thread_.joinable()) return;
  global_ba_abort_ = true;
  global_ba_thread_.join();
}

void LoopCloser::RunGlobalBundleAdjustment(std::uint64_t loop_keyframe_id, std::uint32_t map_id) {
  ScopedTimer timer(timing_, "global_ba");
  spdlog::info("global bundle adjustment of map {} after the loop at keyframe {}", map_id, loop_keyframe_id);
  BundleAdjustmentProblem problem;
  std::vector<KeyFrame*> keyframes;
  std::vector<MapPoint*> points;
  {
    auto lock = map_.ReadLock();
    keyframes = map_.KeyFramesOfMap(map_id);
    for (MapPoint* p : map_.MapPointsOfMap(map_id)) {
      if (!p->is_bad()) points.push_back(p);
    }
    BuildBundleAdjustmentProblem(keyframes, {}, points, &problem, nullptr);
  }
  BundleAdjustmentOptions options;
  options.iterations = options_.global_ba_iterations;
  options.abort = &global_ba_abort_;
  options.refine_without_outliers = false;
  BundleAdjust(problem, options);
  if (global_ba_abort_) {
    ReleaseFreeMemory();
    global_ba_running_ = false;
    return;
  }
  // Apply under a stopped mapper: keyframes created during the BA follow their parents' corrections.
  mapper_.RequestStop();
  while (!mapper_.IsStopped() && !mapper_.IsFinished())
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  {
    auto lock = map_.WriteLock();
    std::unordered_map<const KeyFrame*, size_t> in_ba;
    for (size_t i = 0; i < keyframes.size(); ++i) in_ba[keyframes[i]] = i;
    // Corrections before -> after per keyframe, propagated down the spanning tree.
    std::unordered_map<const KeyFrame*, std::pair<Rigid3d, Rigid3d>> correction;  // (before cw, after cw)
    for (size_t i = 0; i < keyframes.size(); ++i) {
      if (keyframes[i]->is_bad()) continue;
      correction[keyframes[i]] = {keyframes[i]->camera_from_world(), problem.camera_from_world[i]};
    }
    for (KeyFrame* kf : map_.KeyFramesOfMap(map_id)) {
      if (kf->is_bad() || correction.count(kf)) continue;
      // Walk up to an ancestor that has a correction.
      std::vector<KeyFrame*> chain = {kf};
      KeyFrame* a = kf->parent();
      while (a != nullptr && !correction.count(a)) {
        chain.push_back(a);
        a = a->parent();
      }
      if (a == nullptr) continue;
      for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
        KeyFrame* child = *it;
        KeyFrame* parent = child->parent();
        const auto& [parent_before, parent_after] = correction[parent];
        const Rigid3d child_from_parent = child->camera_from_world() * parent_before.Inverse();
        correction[child] = {child->camera_from_world(), child_from_parent * parent_after};
      }
    }
    for (const auto& [kf, c] : correction) const_cast<KeyFrame*>(kf)->SetPose(c.second);
    std::unordered_map<const MapPoint*, size_t> point_index;
    for (size_t j = 0; j < points.size(); ++j) point_index[points[j]] = j;
    for (MapPoint* p : map_.MapPointsOfMap(map_id)) {
      if (p->is_bad()) continue;
      const auto it = point_index.find(p);
      if (it != point_index.end()) {
        p->SetPosition(problem.points[it->second]);
      } else if (p->reference_keyframe() != nullptr) {
        const auto c = correction.find(p->reference_keyframe());
        if (c != correction.end())
          p->SetPosition(c->second.second.Inverse() * (c->second.first * p->position()));
      }
      p->UpdateNormalAndDepth();
    }
    map_.NotifyBigChange();
  }
  mapper_.Release();
  ReleaseFreeMemory();  // the solver's working memory is several times the map's
  ++num_global_ba_;
  global_ba_running_ = false;
  spdlog::info("global bundle adjustment done");
}

}  // namespace semslam
