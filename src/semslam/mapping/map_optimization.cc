#include "semslam/mapping/map_optimization.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <shared_mutex>
#include <unordered_map>
#include <unordered_set>

#include "semslam/core/error.h"
#include "semslam/core/timing.h"
#include "semslam/mapping/gap_link_priors.h"

namespace semslam {

void BuildBundleAdjustmentProblem(const std::vector<KeyFrame*>& keyframes,
                                  const std::vector<KeyFrame*>& fixed_keyframes,
                                  const std::vector<MapPoint*>& points, BundleAdjustmentProblem* problem,
                                  std::vector<ObservationRef>* refs) {
  std::unordered_map<const KeyFrame*, int> pose_index;
  auto add_pose = [&](KeyFrame* kf, bool fixed) {
    pose_index[kf] = static_cast<int>(problem->camera_from_world.size());
    problem->camera_from_world.push_back(kf->camera_from_world());
    problem->pose_fixed.push_back(fixed || kf->is_map_origin());
  };
  for (KeyFrame* kf : keyframes) add_pose(kf, false);
  for (KeyFrame* kf : fixed_keyframes) add_pose(kf, true);
  if (!keyframes.empty()) {
    problem->camera = keyframes.front()->camera();
    if (keyframes.front()->data().stereo) problem->baseline = keyframes.front()->data().stereo->baseline;
  }
  for (size_t j = 0; j < points.size(); ++j) {
    MapPoint* p = points[j];
    problem->points.push_back(p->position());
    for (const auto& [kf, index] : p->observations()) {
      const auto it = pose_index.find(kf);
      if (it == pose_index.end()) continue;
      const FrameData& d = kf->data();
      const Keypoint& kp = d.features.keypoints[static_cast<size_t>(index)];
      BundleAdjustmentObservation obs;
      obs.pose = it->second;
      obs.point = static_cast<int>(j);
      obs.pixel = kp.pixel.cast<double>();
      obs.right_u = d.HasDepth(index) ? d.right_u[static_cast<size_t>(index)] : -1.0;
      obs.inv_sigma2 = d.features.pyramid.inv_sigma2[kp.level];
      problem->observations.push_back(obs);
      if (refs) refs->push_back({kf, p});
    }
  }
}

void DropObservations(Map& map, const std::vector<ObservationRef>& observations) {
  for (const auto& [kf, p] : observations) {
    if (kf->is_bad() || p->is_bad() || p->IndexIn(kf) < 0) continue;
    kf->EraseMapPoint(p);
    p->EraseObservation(kf);
    if (p->is_bad()) map.EraseMapPoint(p);
  }
}

namespace {

std::vector<ObservationRef> Outliers(const BundleAdjustmentResult& result,
                                     const std::vector<ObservationRef>& refs) {
  std::vector<ObservationRef> outliers;
  for (size_t k = 0; k < refs.size() && k < result.outlier.size(); ++k) {
    if (result.outlier[k]) outliers.push_back(refs[k]);
  }
  return outliers;
}

}  // namespace

void ApplyBundleAdjustment(Map& map, const BundleAdjustmentProblem& problem,
                           const BundleAdjustmentResult& result, const std::vector<KeyFrame*>& keyframes,
                           const std::vector<MapPoint*>& points, const std::vector<ObservationRef>& refs,
                           bool drop_outliers) {
  if (drop_outliers) DropObservations(map, Outliers(result, refs));
  for (size_t i = 0; i < keyframes.size(); ++i) {
    if (!problem.pose_fixed[i] && !keyframes[i]->is_bad())
      keyframes[i]->SetPose(problem.camera_from_world[i]);
  }
  for (size_t j = 0; j < points.size(); ++j) {
    if (points[j]->is_bad()) continue;
    points[j]->SetPosition(problem.points[j]);
    points[j]->UpdateNormalAndDepth();
  }
}

void GlobalBundleAdjustmentOptions::Check() const {
  Require(iterations >= 1, "global bundle adjustment: iterations must be >= 1");
  Require(refine_iterations >= 1, "global bundle adjustment: refine_iterations must be >= 1");
  Require(window_keyframes >= 2, "global bundle adjustment: window_keyframes must be >= 2");
}

void LocalScaleOptions::Check() const {
  Require(min_points >= 1, "local scale: min_points must be >= 1");
  Require(std::isfinite(min_spacing_of_depth) && min_spacing_of_depth >= 0,
          "local scale: min_spacing_of_depth must be >= 0");
  Require(std::isfinite(max_spacing_disagreement) && max_spacing_disagreement >= 1,
          "local scale: max_spacing_disagreement must be >= 1");
}

std::vector<std::pair<size_t, size_t>> GlobalBundleAdjustmentWindows(size_t num_keyframes,
                                                                     int window_keyframes) {
  Require(window_keyframes >= 2, "global bundle adjustment: window_keyframes must be >= 2");
  const size_t window = static_cast<size_t>(window_keyframes);
  const size_t count = std::max<size_t>(1, (num_keyframes + window - 1) / window);
  std::vector<std::pair<size_t, size_t>> windows;
  for (size_t w = 0; w < count; ++w)
    windows.emplace_back(num_keyframes * w / count, num_keyframes * (w + 1) / count);
  return windows;
}

namespace {

// One window of a global BA: its keyframes (free) and the live points they observe, started from the poses
// and positions earlier windows found. The other keyframes of the map observing those points hold still:
// where the earlier windows put them, or where the loop correction left them. Holding the later ones matters:
// left out, each window would settle into its own odometry's shape, undoing the loop correction, and the
// sweep would pile those shapes up into drift (a 10,000-frame town: 7.5 m ATE against 1.9 m).
struct WindowProblem {
  std::vector<KeyFrame*> keyframes;  // free, then fixed, as in the problem
  std::vector<MapPoint*> points;
  BundleAdjustmentProblem problem;
  std::vector<ObservationRef> refs;  // per problem observation
};

// Gathers the points from the window's keyframes, so that the cost of a window follows its size, not the
// map's.
WindowProblem BuildWindowProblem(const Map& map, const std::vector<KeyFrame*>& window,
                                 const std::unordered_set<const KeyFrame*>& in_map,
                                 const GlobalBundleAdjustmentResult& earlier) {
  WindowProblem built;
  std::unordered_set<const KeyFrame*> free;
  std::set<MapPoint*, ById> points;  // by id: the same problem on every run
  for (KeyFrame* kf : window) {
    if (kf->is_bad()) continue;
    built.keyframes.push_back(kf);
    free.insert(kf);
    for (MapPoint* p : kf->map_points()) {
      if (p != nullptr && !p->is_bad() && p->observations().count(kf) > 0) points.insert(p);
    }
  }
  std::set<KeyFrame*, ById> fixed;
  for (MapPoint* p : points) {
    for (const auto& [kf, index] : p->observations()) {
      if (!free.count(kf) && in_map.count(kf) && !kf->is_bad()) fixed.insert(kf);
    }
  }
  built.points.assign(points.begin(), points.end());
  const std::vector<KeyFrame*> fixed_keyframes(fixed.begin(), fixed.end());
  BuildBundleAdjustmentProblem(built.keyframes, fixed_keyframes, built.points, &built.problem, &built.refs);
  built.keyframes.insert(built.keyframes.end(), fixed_keyframes.begin(), fixed_keyframes.end());
  AddGapLinkPriors(map, &built.keyframes, &built.problem);
  for (size_t i = 0; i < built.keyframes.size(); ++i) {
    const auto it = earlier.camera_from_world.find(built.keyframes[i]);
    if (it != earlier.camera_from_world.end()) built.problem.camera_from_world[i] = it->second;
  }
  for (size_t j = 0; j < built.points.size(); ++j) {
    const auto it = earlier.positions.find(built.points[j]);
    if (it != earlier.positions.end()) built.problem.points[j] = it->second;
  }
  return built;
}

BundleAdjustmentOptions SolverOptions(const GlobalBundleAdjustmentOptions& options) {
  BundleAdjustmentOptions solver;
  solver.iterations = options.iterations;
  solver.refine_without_outliers = options.drop_outliers;
  solver.refine_iterations = options.refine_iterations;
  solver.abort = options.abort;
  return solver;
}

// The free poses and the points a solved problem holds, by keyframe and point (the problem's order).
void KeepSolution(const BundleAdjustmentProblem& solved, const std::vector<KeyFrame*>& keyframes,
                  const std::vector<MapPoint*>& points, GlobalBundleAdjustmentResult* result) {
  for (size_t i = 0; i < keyframes.size(); ++i) {
    if (!solved.pose_fixed[i]) result->camera_from_world[keyframes[i]] = solved.camera_from_world[i];
  }
  for (size_t j = 0; j < points.size(); ++j) result->positions[points[j]] = solved.points[j];
}

void KeepWindow(const WindowProblem& window, const BundleAdjustmentResult& solved, bool drop_outliers,
                GlobalBundleAdjustmentResult* result) {
  if (drop_outliers) {
    const std::vector<ObservationRef> outliers = Outliers(solved, window.refs);
    result->outliers.insert(result->outliers.end(), outliers.begin(), outliers.end());
  }
  KeepSolution(window.problem, window.keyframes, window.points, result);
}

}  // namespace

GlobalBundleAdjustmentResult AdjustMapInWindows(const Map& map, std::uint32_t map_id,
                                                const GlobalBundleAdjustmentOptions& options, bool lock_map) {
  options.Check();
  GlobalBundleAdjustmentResult result;
  result.map_id = map_id;
  std::vector<KeyFrame*> keyframes;
  {
    std::shared_lock<std::shared_mutex> lock;
    if (lock_map) lock = map.ReadLock();
    keyframes = map.KeyFramesOfMap(map_id);
  }
  const std::unordered_set<const KeyFrame*> in_map(keyframes.begin(), keyframes.end());
  for (const auto& [begin, end] : GlobalBundleAdjustmentWindows(keyframes.size(), options.window_keyframes)) {
    if (options.abort != nullptr && options.abort->load()) break;
    const std::vector<KeyFrame*> window(keyframes.begin() + static_cast<std::ptrdiff_t>(begin),
                                        keyframes.begin() + static_cast<std::ptrdiff_t>(end));
    WindowProblem built;
    {
      std::shared_lock<std::shared_mutex> lock;
      if (lock_map) lock = map.ReadLock();
      built = BuildWindowProblem(map, window, in_map, result);
    }
    ++result.windows;
    if (built.problem.observations.empty()) continue;  // its keyframes were culled meanwhile
    const BundleAdjustmentResult solved = BundleAdjust(built.problem, SolverOptions(options));
    KeepWindow(built, solved, options.drop_outliers, &result);
    if (solved.aborted) break;
  }
  result.aborted = options.abort != nullptr && options.abort->load();
  return result;
}

namespace {

// The median of the keyframe's points' depth after over depth before, and their median depth before; nullopt
// with fewer than `min_points` such points.
std::optional<std::pair<double, double>> DepthRatio(const KeyFrame& kf, const Rigid3d& camera_from_world,
                                                    const GlobalBundleAdjustmentResult& result,
                                                    int min_points) {
  std::vector<double> ratios, depths;
  for (MapPoint* p : kf.map_points()) {
    if (p == nullptr || p->is_bad()) continue;
    const auto moved = result.positions.find(p);
    if (moved == result.positions.end()) continue;
    const double before = (kf.camera_from_world() * p->position()).z();
    const double after = (camera_from_world * moved->second).z();
    if (before > 0.0 && after > 0.0 && std::isfinite(after / before)) {
      ratios.push_back(after / before);
      depths.push_back(before);
    }
  }
  if (ratios.size() < static_cast<size_t>(min_points)) return std::nullopt;
  const auto median = [](std::vector<double>& v) {
    const auto middle = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), middle, v.end());
    return *middle;
  };
  return std::make_pair(median(ratios), median(depths));
}

}  // namespace

std::unordered_map<KeyFrame*, double> LocalScaleChanges(const GlobalBundleAdjustmentResult& result,
                                                        const LocalScaleOptions& options) {
  options.Check();
  struct Moved {
    KeyFrame* kf;
    Eigen::Vector3d center_after;
    double depth_ratio;
    double median_depth;
  };
  std::vector<Moved> moved;  // with enough moved points, along the drive
  for (const auto& [kf, camera_from_world] : result.camera_from_world) {
    if (kf->is_bad()) continue;
    const auto depth = DepthRatio(*kf, camera_from_world, result, options.min_points);
    if (depth) moved.push_back({kf, camera_from_world.Inverse().translation, depth->first, depth->second});
  }
  std::sort(moved.begin(), moved.end(),
            [](const Moved& a, const Moved& b) { return a.kf->id() < b.kf->id(); });
  std::unordered_map<KeyFrame*, double> changes;
  for (size_t i = 0; i < moved.size(); ++i) {
    const Moved& m = moved[i];
    // The step to the next keyframe is what the frames tracked from this one span; the last one has the step
    // before it.
    const auto spacing_ratio = [&](const Moved& other) -> std::optional<double> {
      const double before = (other.kf->center() - m.kf->center()).norm();
      if (before <= options.min_spacing_of_depth * m.median_depth) return std::nullopt;
      const double ratio = (other.center_after - m.center_after).norm() / before;
      if (!(std::abs(std::log(ratio / m.depth_ratio)) <= std::log(options.max_spacing_disagreement)))
        return std::nullopt;
      return ratio;
    };
    std::optional<double> change;
    if (i + 1 < moved.size()) change = spacing_ratio(moved[i + 1]);
    if (!change && i > 0) change = spacing_ratio(moved[i - 1]);
    changes[m.kf] = change.value_or(m.depth_ratio);
  }
  return changes;
}

std::unordered_map<KeyFrame*, double> LocalScaleChanges(const BundleAdjustmentProblem& solved,
                                                        const std::vector<KeyFrame*>& keyframes,
                                                        const std::vector<MapPoint*>& points,
                                                        const LocalScaleOptions& options) {
  Require(keyframes.size() == solved.camera_from_world.size() && points.size() == solved.points.size(),
          "local scale: the keyframes and points must be those of the problem");
  GlobalBundleAdjustmentResult moved;
  KeepSolution(solved, keyframes, points, &moved);
  return LocalScaleChanges(moved, options);
}

void FollowLocalScaleChanges(const std::unordered_map<KeyFrame*, double>& changes) {
  for (const auto& [kf, change] : changes) kf->CorrectScale(change);
}

int WriteGlobalBundleAdjustment(Map& map, const GlobalBundleAdjustmentResult& result,
                                bool follow_local_scale) {
  std::unordered_map<KeyFrame*, double> stretch;
  if (follow_local_scale) stretch = LocalScaleChanges(result);
  FollowLocalScaleChanges(stretch);
  DropObservations(map, result.outliers);
  struct Correction {
    Rigid3d before_cw, after_cw;
    double stretch = 1.0;
  };
  std::unordered_map<KeyFrame*, Correction> correction;
  for (const auto& [kf, camera_from_world] : result.camera_from_world) {
    if (kf->is_bad()) continue;
    const auto s = stretch.find(kf);
    correction[kf] = {kf->camera_from_world(), camera_from_world, s != stretch.end() ? s->second : 1.0};
  }
  // Keyframes made since: each follows its nearest ancestor in the result, stretched with it.
  int followers = 0;
  for (KeyFrame* kf : map.KeyFramesOfMap(result.map_id)) {
    if (kf->is_bad() || correction.count(kf)) continue;
    std::vector<KeyFrame*> chain = {kf};
    KeyFrame* a = kf->parent();
    while (a != nullptr && !correction.count(a)) {
      chain.push_back(a);
      a = a->parent();
    }
    if (a == nullptr) continue;
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      KeyFrame* child = *it;
      const Correction& parent = correction.at(child->parent());
      const Rigid3d child_from_parent = child->camera_from_world() * parent.before_cw.Inverse();
      correction[child] = {child->camera_from_world(),
                           Stretched(child_from_parent, parent.stretch) * parent.after_cw, parent.stretch};
      child->CorrectScale(parent.stretch);
      ++followers;
    }
  }
  for (const auto& [kf, c] : correction) kf->SetPose(c.after_cw);
  // Points the result holds take their place; the others (made since, or left out) follow their reference.
  for (MapPoint* p : map.MapPointsOfMap(result.map_id)) {
    if (p->is_bad()) continue;
    const auto it = result.positions.find(p);
    if (it != result.positions.end()) {
      p->SetPosition(it->second);
    } else {
      const auto c =
          p->reference_keyframe() != nullptr ? correction.find(p->reference_keyframe()) : correction.end();
      if (c == correction.end()) continue;
      p->SetPosition(c->second.after_cw.Inverse() *
                     (c->second.stretch * (c->second.before_cw * p->position())));
    }
    p->UpdateNormalAndDepth();
  }
  return followers;
}

namespace {

WindowProblem BuildSpreadProblem(const Map& map, const std::vector<KeyFrame*>& keyframes,
                                 size_t max_keyframes);

// A solved spread problem as a result to write: every keyframe of it (the fixed ones where they are), its
// points and outliers; the keyframes between follow them (WriteGlobalBundleAdjustment).
GlobalBundleAdjustmentResult SpreadResult(std::uint32_t map_id, const WindowProblem& spread,
                                          const BundleAdjustmentResult& solved, bool drop_outliers) {
  GlobalBundleAdjustmentResult result;
  result.map_id = map_id;
  KeepWindow(spread, solved, drop_outliers, &result);
  for (size_t i = 0; i < spread.keyframes.size(); ++i) {
    result.camera_from_world.emplace(spread.keyframes[i], spread.problem.camera_from_world[i]);
  }
  result.windows = 1;
  return result;
}

}  // namespace

void GlobalBundleAdjustment(Map& map, std::uint32_t map_id, const GlobalBundleAdjustmentOptions& options) {
  options.Check();
  const std::vector<KeyFrame*> keyframes = map.KeyFramesOfMap(map_id);
  if (keyframes.size() > static_cast<size_t>(options.window_keyframes)) {
    // Windows hold the keyframes around them still, which keeps a map's large-scale shape as it is: that
    // shape comes from a spread of the map's keyframes first, which the others follow.
    WindowProblem spread = BuildSpreadProblem(map, keyframes, static_cast<size_t>(options.window_keyframes));
    if (!spread.problem.observations.empty()) {
      const BundleAdjustmentResult solved = BundleAdjust(spread.problem, SolverOptions(options));
      WriteGlobalBundleAdjustment(map, SpreadResult(map_id, spread, solved, options.drop_outliers),
                                  options.follow_local_scale);
    }
  }
  WriteGlobalBundleAdjustment(map, AdjustMapInWindows(map, map_id, options, /*lock_map=*/false),
                              options.follow_local_scale);
  ReleaseFreeMemory();
}

void SelfCalibrationOptions::Check() const {
  Require(std::isfinite(min_cost_reduction) && min_cost_reduction >= 0 && min_cost_reduction < 1,
          "self-calibration: min_cost_reduction must be in [0, 1)");
  Require(min_keyframes >= 3, "self-calibration: min_keyframes must be at least 3");
  Require(std::isfinite(max_focal_change) && max_focal_change >= 0,
          "self-calibration: max_focal_change must be >= 0");
  Require(std::isfinite(max_principal_point_shift) && max_principal_point_shift >= 0,
          "self-calibration: max_principal_point_shift must be >= 0");
  Require(std::isfinite(max_radial) && max_radial >= 0, "self-calibration: max_radial must be >= 0");
}

void ExpressKeyFramesInCamera(Map& map, std::uint32_t map_id, const PinholeCamera& camera) {
  camera.Check();
  for (KeyFrame* kf : map.KeyFramesOfMap(map_id)) {
    const FrameData& d = kf->data();
    kf->ReplaceData(MakeFrameData(camera, d.stereo, d.features, d.right_u, d.depth));
  }
}

namespace {

// Why a refined camera is not kept (empty: it is).
std::string RefusalReason(const PinholeCamera& nominal, const PinholeCamera& refined, double plain_cost,
                          double refined_cost, const SelfCalibrationOptions& calibration) {
  if (plain_cost - refined_cost < calibration.min_cost_reduction * plain_cost) {
    return "it lowered the cost too little to be told from noise";
  }
  if (std::abs(refined.fx / nominal.fx - 1.0) > calibration.max_focal_change) {
    return fmt::format("the focal length moved more than {:g} %", 100 * calibration.max_focal_change);
  }
  if (std::abs(refined.cx - nominal.cx) > calibration.max_principal_point_shift * nominal.width ||
      std::abs(refined.cy - nominal.cy) > calibration.max_principal_point_shift * nominal.height) {
    return fmt::format("the principal point moved more than {:g} % of the image",
                       100 * calibration.max_principal_point_shift);
  }
  if (std::abs(refined.distortion.k1) > calibration.max_radial ||
      std::abs(refined.distortion.k2) > calibration.max_radial) {
    return fmt::format("the radial distortion came out above {:g}", calibration.max_radial);
  }
  return {};
}

// Every k-th keyframe of a map too large for one window (its origin among them), fewer than `max_keyframes`,
// and the points two of them or more observe: the whole map's geometry, and its loops, at the cost of one
// window. The ends of gap links are among them, held as the map has them relative to each other.
WindowProblem BuildSpreadProblem(const Map& map, const std::vector<KeyFrame*>& keyframes,
                                 size_t max_keyframes) {
  const size_t step = (keyframes.size() + max_keyframes - 1) / max_keyframes;
  const std::unordered_set<const KeyFrame*> link_ends = GapLinkEnds(map);
  WindowProblem built;
  for (size_t i = 0; i < keyframes.size(); ++i) {
    KeyFrame* kf = keyframes[i];
    if (!kf->is_bad() && (i % step == 0 || kf->is_map_origin() || link_ends.count(kf)))
      built.keyframes.push_back(kf);
  }
  std::map<MapPoint*, int, ById> seen;  // by id: the same problem on every run
  for (KeyFrame* kf : built.keyframes) {
    for (MapPoint* p : kf->map_points()) {
      if (p != nullptr && !p->is_bad() && p->observations().count(kf) > 0) ++seen[p];
    }
  }
  for (const auto& [p, n] : seen) {
    if (n >= 2) built.points.push_back(p);
  }
  BuildBundleAdjustmentProblem(built.keyframes, {}, built.points, &built.problem, &built.refs);
  AddGapLinkPriors(map, &built.keyframes, &built.problem);
  return built;
}

}  // namespace

IntrinsicsRefinement SelfCalibratingGlobalBundleAdjustment(Map& map, std::uint32_t map_id,
                                                           const GlobalBundleAdjustmentOptions& options,
                                                           const SelfCalibrationOptions& calibration) {
  options.Check();
  calibration.Check();
  IntrinsicsRefinement refinement;
  refinement.map_id = map_id;
  const std::vector<KeyFrame*> keyframes = map.KeyFramesOfMap(map_id);
  if (keyframes.empty()) return refinement;
  refinement.nominal = keyframes.front()->camera();
  refinement.refined = refinement.nominal;
  if (keyframes.size() > static_cast<size_t>(options.window_keyframes)) {
    // The camera is the whole map's: it is told from a spread of keyframes that fits one window (which also
    // gives the map its large-scale shape, as in GlobalBundleAdjustment), and the map, adjusted in windows
    // after, takes it.
    WindowProblem spread = BuildSpreadProblem(map, keyframes, static_cast<size_t>(options.window_keyframes));
    BundleAdjustmentOptions solver = SolverOptions(options);
    const bool stereo = std::any_of(spread.problem.observations.begin(), spread.problem.observations.end(),
                                    [](const BundleAdjustmentObservation& o) { return o.right_u >= 0; });
    if (stereo || spread.problem.observations.empty()) {
      refinement.reason = stereo ? "the map has stereo observations" : "the map's keyframes share no points";
      GlobalBundleAdjustment(map, map_id, options);
      return refinement;
    }
    const BundleAdjustmentResult plain = BundleAdjust(spread.problem, solver);
    const GlobalBundleAdjustmentResult plain_result =
        SpreadResult(map_id, spread, plain, options.drop_outliers);
    refinement.plain_cost = plain.final_capped_chi2;
    solver.refine_intrinsics = true;
    const BundleAdjustmentResult result = BundleAdjust(spread.problem, solver);
    refinement.refined = *result.refined_camera;
    refinement.refined_cost = result.final_capped_chi2;
    refinement.reason = RefusalReason(refinement.nominal, refinement.refined, refinement.plain_cost,
                                      refinement.refined_cost, calibration);
    refinement.accepted = refinement.reason.empty();
    if (refinement.accepted) {
      WriteGlobalBundleAdjustment(map, SpreadResult(map_id, spread, result, false),
                                  options.follow_local_scale);
      ExpressKeyFramesInCamera(map, map_id, refinement.refined);
    } else {
      WriteGlobalBundleAdjustment(map, plain_result, options.follow_local_scale);
    }
    WriteGlobalBundleAdjustment(map, AdjustMapInWindows(map, map_id, options, /*lock_map=*/false),
                                options.follow_local_scale);
    ReleaseFreeMemory();
    return refinement;
  }
  if (keyframes.size() < static_cast<size_t>(calibration.min_keyframes)) {
    GlobalBundleAdjustment(map, map_id, options);
    refinement.reason = fmt::format("the map's {} keyframes are too few to tell the camera ({} at least)",
                                    keyframes.size(), calibration.min_keyframes);
    return refinement;
  }
  // The plain BA first: the map keeps its result unless the refinement earns its five parameters.
  WindowProblem whole = BuildWindowProblem(map, keyframes, {}, {});
  BundleAdjustmentProblem& problem = whole.problem;
  BundleAdjustmentOptions solver = SolverOptions(options);
  // The keyframes follow the stretch of each solution the map takes (the problem holds it after the solve).
  const auto follow_local_scale = [&] {
    if (!options.follow_local_scale) return;
    FollowLocalScaleChanges(LocalScaleChanges(problem, whole.keyframes, whole.points));
  };
  const BundleAdjustmentResult plain = BundleAdjust(problem, solver);
  follow_local_scale();
  ApplyBundleAdjustment(map, problem, plain, whole.keyframes, whole.points, whole.refs,
                        options.drop_outliers);
  refinement.plain_cost = plain.final_capped_chi2;
  const bool monocular = std::none_of(problem.observations.begin(), problem.observations.end(),
                                      [](const BundleAdjustmentObservation& o) { return o.right_u >= 0; });
  if (!monocular) {
    refinement.reason = "the map has stereo observations";
  } else if (!problem.observations.empty()) {
    solver.refine_intrinsics = true;
    const BundleAdjustmentResult result = BundleAdjust(problem, solver);
    const PinholeCamera& nominal = problem.camera;
    const PinholeCamera& refined = *result.refined_camera;
    refinement.refined = refined;
    refinement.refined_cost = result.final_capped_chi2;
    refinement.reason =
        RefusalReason(nominal, refined, refinement.plain_cost, refinement.refined_cost, calibration);
    if (refinement.reason.empty()) {
      refinement.accepted = true;
      follow_local_scale();
      ApplyBundleAdjustment(map, problem, result, whole.keyframes, whole.points, {}, false);
      ExpressKeyFramesInCamera(map, map_id, refined);
    }
  }
  ReleaseFreeMemory();
  return refinement;
}

}  // namespace semslam
