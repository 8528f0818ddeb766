// LoopCloser, the correction side: moving a map onto another (merges), correcting the keyframes and points
// around a loop, the essential graph and the global bundle adjustment after it.

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <unordered_map>

#include "semslam/core/error.h"
#include "semslam/core/thread_priority.h"
#include "semslam/geometry/scale_across_gap.h"
#include "semslam/loop/loop_closer.h"
#include "semslam/map/map_matcher.h"
#include "semslam/mapping/local_mapper.h"
#include "semslam/mapping/map_optimization.h"
#include "semslam/optim/bundle_adjustment.h"
#include "semslam/optim/pose_graph.h"
#include "semslam/optim/sim3_optimization.h"

namespace semslam {

namespace {

// A gap link's prediction is rough (the motion of before a loss carried over it): its information is this
// share of a covisibility edge's.
constexpr double kGapLinkWeight = 0.1;

// How much lower than the pipeline's other threads the global BA runs.
constexpr int kGlobalBundleAdjustmentNiceness = 10;

// A gap link's scale comes from the drive's speed over this many keyframes on each side of the gap.
constexpr int kSpeedKeyframes = 5;

// The poses of `kf` and of up to kSpeedKeyframes keyframes of its session nearest to it in time, before it
// (or after it, `later`), in time order.
Trajectory DriveBeside(const std::vector<KeyFrame*>& keyframes, const KeyFrame* kf, bool later) {
  std::vector<const KeyFrame*> side;
  for (const KeyFrame* other : keyframes) {
    if (other->is_bad() || other->session() != kf->session()) continue;
    if (later ? other->timestamp() > kf->timestamp() : other->timestamp() < kf->timestamp())
      side.push_back(other);
  }
  const auto nearer = [kf](const KeyFrame* a, const KeyFrame* b) {
    return std::abs(a->timestamp() - kf->timestamp()) < std::abs(b->timestamp() - kf->timestamp());
  };
  if (side.size() > kSpeedKeyframes) {
    std::nth_element(side.begin(), side.begin() + kSpeedKeyframes, side.end(), nearer);
    side.resize(kSpeedKeyframes);
  }
  side.push_back(kf);
  std::sort(side.begin(), side.end(),
            [](const KeyFrame* a, const KeyFrame* b) { return a->timestamp() < b->timestamp(); });
  Trajectory poses;
  for (const KeyFrame* other : side) poses.push_back({other->timestamp(), other->world_from_camera()});
  return poses;
}

}  // namespace

double LoopCloser::MoveMapToMatchedFrame(KeyFrame* current) {
  // current_from_world_ is the current keyframe's pose in the matched map's frame: the same transform takes
  // every pose and point of its map there (with the scale between the two, monocular).
  const std::uint32_t from = current->map_id(), into = matched_keyframe_->map_id();
  const Sim3d into_from_current_map = current_from_world_.Inverse() * Sim3d(current->camera_from_world());
  const Sim3d current_map_from_into = into_from_current_map.Inverse();
  for (MapPoint* p : map_.MapPointsOfMap(from)) {
    p->SetPosition(into_from_current_map * p->position());
    p->UpdateNormalAndDepth();
  }
  for (KeyFrame* kf : map_.KeyFramesOfMap(from)) {
    kf->SetPose(RigidPose(Sim3d(kf->camera_from_world()) * current_map_from_into));
    kf->CorrectScale(into_from_current_map.scale);
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
      "{} detected: keyframe {} (map {}, t {:.1f} s) matches keyframe {} (map {}, t {:.1f} s), {} matches, "
      "confirmed by {} neighbours",
      merge ? "map merge" : "loop", current->id(), current->map_id(), current->timestamp(),
      matched_keyframe_->id(), matched_keyframe_->map_id(), matched_keyframe_->timestamp(), last_matches_,
      last_verified_);
  mapper_.RequestStop();
  StopGlobalBundleAdjustment();
  while (!mapper_.IsStopped() && !mapper_.IsFinished())
    std::this_thread::sleep_for(std::chrono::milliseconds(1));

  LoopEvent event;
  event.query_keyframe = current->id();
  event.matched_keyframe = matched_keyframe_->id();
  event.query_timestamp = current->timestamp();
  event.matched_timestamp = matched_keyframe_->timestamp();
  event.matches = last_matches_;
  event.verified_neighbours = last_verified_;
  event.scale = current_from_world_.scale;
  event.merge = merge;
  event.map_id = current->map_id();
  event.matched_map_id = matched_keyframe_->map_id();

  LinksById loop_connections;
  PosesById corrected, non_corrected;
  {
    auto lock = map_.WriteLock();
    if (merge) {
      event.scale = MoveMapToMatchedFrame(current);
      // The move took the whole map into the matched map's units: what is left to correct is a loop of scale
      // 1. Keeping the transform's scale here scaled the current keyframe's neighbourhood a second time (a
      // monocular town merged at scale 1.54 came out 6-8 % long over its whole younger map).
      current_from_world_ = Sim3d(current->camera_from_world());
    }
    current->UpdateConnections();
    std::vector<KeyFrame*> connected = current->Covisibles();
    connected.push_back(current);
    const Rigid3d world_from_current = current->world_from_camera();
    const LoopCorrectionSize correction =
        MeasureCorrection(current->camera_from_world(), current_from_world_);
    event.correction_m = correction.metres;
    event.correction_deg = correction.degrees;

    // Propagate the correction to the keyframes around the current one through their relative poses.
    corrected[current] = current_from_world_;
    for (KeyFrame* kf : connected) {
      const Sim3d original = Sim3d(kf->camera_from_world());
      non_corrected[kf] = original;
      if (kf != current) {
        const Sim3d kf_from_current = Sim3d(kf->camera_from_world() * world_from_current);
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
      kf->SetPose(RigidPose(corrected_pose));
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
      std::set<KeyFrame*, ById> links(kf->Covisibles().begin(), kf->Covisibles().end());
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
                                        const PosesById& non_corrected, const PosesById& corrected,
                                        const LinksById& loop_connections) {
  ScopedTimer timer(timing_, "essential_graph");
  constexpr int kMinWeight = 100;
  const std::vector<KeyFrame*> keyframes = map_.KeyFramesOfMap(current->map_id());
  PoseGraph graph;
  std::unordered_map<const KeyFrame*, int> node;
  std::unordered_map<const KeyFrame*, Sim3d> before;  // camera_from_world used for relative measurements
  for (KeyFrame* kf : keyframes) {
    if (kf->is_bad()) continue;
    const auto c = corrected.find(kf);
    const Sim3d camera_from_world = c != corrected.end() ? c->second : Sim3d(kf->camera_from_world());
    const auto nc = non_corrected.find(kf);
    before[kf] = nc != non_corrected.end() ? nc->second : Sim3d(kf->camera_from_world());
    // Only the matched keyframe holds still: it fixes the graph's frame and scale. Holding the map's origin too
    // fixed the chain between the two (its length and turn), and the correction piled up beside them (a merged
    // monocular town came out bent in a zigzag at its start: 6-8 m ATE against 1.6 m).
    node[kf] = graph.AddNode(camera_from_world.Inverse(), kf == loop_keyframe);
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
  // Gap links (map/map.h): the only tie between the two sides of a loss once their maps are merged. Without
  // it the younger map hangs from the one place the merge saw: no cycle closes, and neither side's drift is
  // corrected. A monocular link carries the scale between its sides too, from the car's speed on both
  // (geometry/scale_across_gap.h): a merge scales the younger map as it fits at the place that merged it,
  // which may lie far along the drive, so its units may still differ at the gap.
  for (const GapLink& link : map_.gap_links()) {
    const std::optional<GapEdge> edge = ResolveGapLink(link);
    if (!edge) continue;
    const auto ia = node.find(edge->before), ib = node.find(edge->after);
    if (ia == node.end() || ib == node.end()) continue;
    Sim3d before_from_after(edge->before_from_after);
    if (!options_.fix_scale) {
      const std::optional<double> scale = FitScaleAcrossGap(DriveBeside(keyframes, edge->before, false),
                                                            DriveBeside(keyframes, edge->after, true));
      if (scale) before_from_after.scale = *scale;
    }
    spdlog::info("gap link keyframe {} -> {}: a map unit after the gap is {:.3f} before it",
                 edge->before->id(), edge->after->id(), before_from_after.scale);
    graph.AddRelativeEdge(ia->second, ib->second, before_from_after, kGapLinkWeight);
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
    const_cast<KeyFrame*>(kf)->SetPose(RigidPose(camera_from_world));
    // Its points move by world_from_kf * before: the map around it is stretched by the node's scale.
    const_cast<KeyFrame*>(kf)->CorrectScale(world_from_kf.scale);
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
  // It may take many seconds; on a machine with fewer cores than the pipeline has threads it would otherwise
  // slow the local mapper while the drive goes on into places no loop will correct.
  if (options_.global_ba_low_priority) LowerCurrentThreadPriority(kGlobalBundleAdjustmentNiceness);
  ScopedTimer timer(timing_, "global_ba");
  spdlog::info("global bundle adjustment of map {} after the loop at keyframe {}", map_id, loop_keyframe_id);
  GlobalBundleAdjustmentOptions options;
  options.iterations = options_.global_ba_iterations;
  options.refine_iterations = options_.global_ba_iterations;
  options.window_keyframes = options_.global_ba_window_keyframes;
  options.abort = &global_ba_abort_;
  const GlobalBundleAdjustmentResult adjusted = AdjustMapInWindows(map_, map_id, options, /*lock_map=*/true);
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
    // Monocular: the frames kept relative to a keyframe stretch with the map around it.
    const int followers =
        WriteGlobalBundleAdjustment(map_, adjusted, /*follow_local_scale=*/!options_.fix_scale);
    if (followers > 0)
      spdlog::info("{} keyframe{} made during the global BA followed {} ancestors", followers,
                   followers == 1 ? "" : "s", followers == 1 ? "its" : "their");
    map_.NotifyBigChange();
  }
  mapper_.Release();
  ReleaseFreeMemory();  // the solver's working memory is several times the map's
  ++num_global_ba_;
  global_ba_running_ = false;
  spdlog::info("global bundle adjustment done ({} window{}, {} observations failed the chi-square test and "
               "were dropped)",
               adjusted.windows, adjusted.windows == 1 ? "" : "s", adjusted.outliers.size());
}

}  // namespace semslam
