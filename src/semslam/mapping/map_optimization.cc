#include "semslam/mapping/map_optimization.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "semslam/core/timing.h"
#include "semslam/optim/sim3_optimization.h"

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

void ApplyBundleAdjustment(Map& map, const BundleAdjustmentProblem& problem,
                           const BundleAdjustmentResult& result, const std::vector<KeyFrame*>& keyframes,
                           const std::vector<MapPoint*>& points, const std::vector<ObservationRef>& refs,
                           bool drop_outliers) {
  if (drop_outliers) {
    for (size_t k = 0; k < refs.size() && k < result.outlier.size(); ++k) {
      if (!result.outlier[k]) continue;
      KeyFrame* kf = refs[k].keyframe;
      MapPoint* p = refs[k].point;
      if (kf->is_bad() || p->is_bad()) continue;
      kf->EraseMapPoint(p);
      p->EraseObservation(kf);
      if (p->is_bad()) map.EraseMapPoint(p);
    }
  }
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

namespace {

// Every keyframe and live point of one map of the atlas, as a bundle-adjustment problem.
struct WholeMapProblem {
  std::vector<KeyFrame*> keyframes;
  std::vector<MapPoint*> points;
  BundleAdjustmentProblem problem;
  std::vector<ObservationRef> refs;
};

WholeMapProblem BuildWholeMapProblem(const Map& map, std::uint32_t map_id) {
  WholeMapProblem whole;
  whole.keyframes = map.KeyFramesOfMap(map_id);
  for (MapPoint* p : map.MapPointsOfMap(map_id)) {
    if (!p->is_bad()) whole.points.push_back(p);
  }
  BuildBundleAdjustmentProblem(whole.keyframes, {}, whole.points, &whole.problem, &whole.refs);
  return whole;
}

// Runs the BA (keeping every observation) and writes its result into the map.
BundleAdjustmentResult AdjustWholeMap(Map& map, WholeMapProblem& whole, const BundleAdjustmentOptions& options) {
  const BundleAdjustmentResult result = BundleAdjust(whole.problem, options);
  ApplyBundleAdjustment(map, whole.problem, result, whole.keyframes, whole.points, whole.refs, false);
  return result;
}

BundleAdjustmentOptions WholeMapOptions(int iterations) {
  BundleAdjustmentOptions options;
  options.iterations = iterations;
  options.refine_without_outliers = false;
  return options;
}

}  // namespace

void GlobalBundleAdjustment(Map& map, std::uint32_t map_id, int iterations, std::atomic<bool>* abort) {
  WholeMapProblem whole = BuildWholeMapProblem(map, map_id);
  BundleAdjustmentOptions options = WholeMapOptions(iterations);
  options.abort = abort;
  AdjustWholeMap(map, whole, options);
  ReleaseFreeMemory();
}

IntrinsicsRefinement SelfCalibratingGlobalBundleAdjustment(Map& map, std::uint32_t map_id, int iterations,
                                                           double min_cost_reduction) {
  IntrinsicsRefinement refinement;
  refinement.map_id = map_id;
  WholeMapProblem whole = BuildWholeMapProblem(map, map_id);
  BundleAdjustmentProblem& problem = whole.problem;
  refinement.nominal = problem.camera;
  refinement.refined = problem.camera;
  // The plain BA first: the map keeps its result unless the refinement earns its five parameters.
  BundleAdjustmentOptions options = WholeMapOptions(iterations);
  const BundleAdjustmentResult plain = AdjustWholeMap(map, whole, options);
  refinement.plain_cost = plain.final_capped_chi2;
  const bool monocular = std::none_of(problem.observations.begin(), problem.observations.end(),
                                      [](const BundleAdjustmentObservation& o) { return o.right_u >= 0; });
  if (!monocular) {
    refinement.reason = "the map has stereo observations";
  } else if (!problem.observations.empty()) {
    options.refine_intrinsics = true;
    const BundleAdjustmentResult result = BundleAdjust(problem, options);
    const PinholeCamera& nominal = problem.camera;
    const PinholeCamera& refined = *result.refined_camera;
    refinement.refined = refined;
    refinement.refined_cost = result.final_capped_chi2;
    if (refinement.plain_cost - refinement.refined_cost < min_cost_reduction * refinement.plain_cost) {
      refinement.reason = "it lowered the cost too little to be told from noise";
    } else if (std::abs(refined.fx / nominal.fx - 1.0) > 0.10) {
      refinement.reason = "the focal length moved more than 10 %";
    } else if (std::abs(refined.cx - nominal.cx) > 0.05 * nominal.width ||
               std::abs(refined.cy - nominal.cy) > 0.05 * nominal.height) {
      refinement.reason = "the principal point moved more than 5 % of the image";
    } else if (std::abs(refined.distortion.k1) > 0.2 || std::abs(refined.distortion.k2) > 0.2) {
      refinement.reason = "the radial distortion came out above 0.2";
    } else {
      refinement.accepted = true;
      ApplyBundleAdjustment(map, problem, result, whole.keyframes, whole.points, whole.refs, false);
    }
  }
  ReleaseFreeMemory();
  return refinement;
}

int RefineSim3(const KeyFrame& kf1, const KeyFrame& kf2, std::vector<MapPoint*>& matches12,
               Sim3d* kf1_from_kf2, double chi2_threshold, bool fix_scale) {
  Sim3RefinementProblem problem;
  problem.camera1 = kf1.camera();
  problem.camera2 = kf2.camera();
  std::vector<size_t> slots;
  for (size_t i = 0; i < matches12.size(); ++i) {
    MapPoint* p1 = kf1.map_point(static_cast<int>(i));
    MapPoint* p2 = matches12[i];
    if (p1 == nullptr || p2 == nullptr || p1->is_bad() || p2->is_bad()) continue;
    const int i2 = p2->IndexIn(&kf2);
    if (i2 < 0) continue;
    const Keypoint& kp1 = kf1.features().keypoints[i];
    const Keypoint& kp2 = kf2.features().keypoints[static_cast<size_t>(i2)];
    Sim3Match m;
    m.point1 = kf1.camera_from_world() * p1->position();
    m.point2 = kf2.camera_from_world() * p2->position();
    m.pixel1 = kp1.pixel.cast<double>();
    m.pixel2 = kp2.pixel.cast<double>();
    m.inv_sigma2_1 = kf1.features().pyramid.inv_sigma2[kp1.level];
    m.inv_sigma2_2 = kf2.features().pyramid.inv_sigma2[kp2.level];
    problem.matches.push_back(m);
    slots.push_back(i);
  }
  if (problem.matches.size() < 3) return 0;
  const Sim3RefinementResult result = OptimizeSim3(problem, *kf1_from_kf2, chi2_threshold, fix_scale);
  int inliers = 0;
  for (size_t k = 0; k < slots.size(); ++k) {
    if (result.inliers[k]) {
      ++inliers;
    } else {
      matches12[slots[k]] = nullptr;
    }
  }
  *kf1_from_kf2 = result.camera1_from_camera2;
  return inliers;
}

}  // namespace semslam
