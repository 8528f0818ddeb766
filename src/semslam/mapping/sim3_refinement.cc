#include "semslam/mapping/sim3_refinement.h"

#include <cmath>

#include "semslam/core/error.h"
#include "semslam/geometry/sim3_solver.h"
#include "semslam/map/keyframe_matches.h"
#include "semslam/optim/sim3_optimization.h"

namespace semslam {

int RefineSim3(const KeyFrame& kf1, const KeyFrame& kf2, std::vector<MapPoint*>& matches12,
               Sim3d* kf1_from_kf2, double chi2_threshold, bool fix_scale) {
  Sim3RefinementProblem problem;
  problem.camera1 = kf1.camera();
  problem.camera2 = kf2.camera();
  const std::vector<KeyFramePointMatch> usable = MatchesInCameraFrames(kf1, kf2, matches12);
  for (const KeyFramePointMatch& u : usable) {
    const Keypoint& kp1 = kf1.features().keypoints[u.slot1];
    const Keypoint& kp2 = kf2.features().keypoints[u.slot2];
    Sim3Match m;
    m.point1 = u.point1;
    m.point2 = u.point2;
    m.pixel1 = kp1.pixel.cast<double>();
    m.pixel2 = kp2.pixel.cast<double>();
    m.inv_sigma2_1 = kf1.features().pyramid.inv_sigma2[kp1.level];
    m.inv_sigma2_2 = kf2.features().pyramid.inv_sigma2[kp2.level];
    problem.matches.push_back(m);
  }
  if (problem.matches.size() < 3) return 0;
  const Sim3RefinementResult result = OptimizeSim3(problem, *kf1_from_kf2, chi2_threshold, fix_scale);
  int inliers = 0;
  for (size_t k = 0; k < usable.size(); ++k) {
    if (result.inliers[k]) {
      ++inliers;
    } else {
      matches12[usable[k].slot1] = nullptr;
    }
  }
  *kf1_from_kf2 = result.camera1_from_camera2;
  return inliers;
}

std::optional<double> StructureDepthRatio(const KeyFrame& kf1, const KeyFrame& kf2,
                                          const std::vector<MapPoint*>& matches12,
                                          const Sim3d& kf1_from_kf2) {
  Points3d points1, points2;
  for (const KeyFramePointMatch& m : MatchesInCameraFrames(kf1, kf2, matches12)) {
    points1.push_back(m.point1);
    points2.push_back(m.point2);
  }
  if (points1.empty()) return std::nullopt;
  return MedianDepthRatio(kf1_from_kf2, points1, points2);
}

MonocularSim3Refinement RefineSim3KeepingStructureScale(const KeyFrame& kf1, const KeyFrame& kf2,
                                                        std::vector<MapPoint*>& matches12,
                                                        Sim3d* kf1_from_kf2, double chi2_threshold,
                                                        double max_depth_ratio) {
  Require(std::isfinite(max_depth_ratio) && max_depth_ratio > 1.0,
          "sim3 refinement: max_depth_ratio must be > 1");
  const std::vector<MapPoint*> initial_matches = matches12;
  MonocularSim3Refinement refinement;
  refinement.inliers = RefineSim3(kf1, kf2, matches12, kf1_from_kf2, chi2_threshold, /*fix_scale=*/false);
  refinement.free_scale = kf1_from_kf2->scale;
  const std::optional<double> ratio = StructureDepthRatio(kf1, kf2, matches12, *kf1_from_kf2);
  refinement.free_depth_ratio = ratio.value_or(0.0);
  if (!ratio || !std::isfinite(*ratio) || *ratio <= 0.0) return refinement;  // nothing to rescale by
  if (DepthRatioWithin(*ratio, max_depth_ratio)) return refinement;
  // The scale at which the matched points would keep their own depth (exactly so for cameras at one place).
  refinement.scale_held = true;
  matches12 = initial_matches;
  kf1_from_kf2->scale *= *ratio;
  refinement.inliers = RefineSim3(kf1, kf2, matches12, kf1_from_kf2, chi2_threshold, /*fix_scale=*/true);
  return refinement;
}

}  // namespace semslam
