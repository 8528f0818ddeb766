#include "semslam/mapping/map_optimization.h"

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

void GlobalBundleAdjustment(Map& map, std::uint32_t map_id, int iterations, std::atomic<bool>* abort) {
  const std::vector<KeyFrame*> keyframes = map.KeyFramesOfMap(map_id);
  std::vector<MapPoint*> points;
  for (MapPoint* p : map.MapPointsOfMap(map_id)) {
    if (!p->is_bad()) points.push_back(p);
  }
  BundleAdjustmentProblem problem;
  std::vector<ObservationRef> refs;
  BuildBundleAdjustmentProblem(keyframes, {}, points, &problem, &refs);
  BundleAdjustmentOptions options;
  options.iterations = iterations;
  options.abort = abort;
  options.refine_without_outliers = false;
  const BundleAdjustmentResult result = BundleAdjust(problem, options);
  ApplyBundleAdjustment(map, problem, result, keyframes, points, refs, false);
  ReleaseFreeMemory();
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
