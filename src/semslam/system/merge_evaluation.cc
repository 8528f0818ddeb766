#include "semslam/system/merge_evaluation.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace semslam {
namespace {

// The true pose at `timestamp` (within a millisecond), or null.
const Rigid3d* TruePoseAt(const Trajectory& truth, double timestamp) {
  const auto it = std::lower_bound(truth.begin(), truth.end(), timestamp - 1e-3,
                                   [](const StampedPose& p, double t) { return p.timestamp < t; });
  if (it == truth.end() || std::abs(it->timestamp - timestamp) > 1e-3) return nullptr;
  return &it->world_from_camera;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

nlohmann::json EvaluateMergedLandmarks(const std::vector<PlacedLandmark>& placed,
                                       const std::vector<FramePose>& keyframes,
                                       const std::map<std::uint32_t, Trajectory>& truths,
                                       const Sim3d& town_from_map,
                                       const std::vector<SceneTruth::Landmark>& truth_landmarks) {
  std::map<std::string, const SceneTruth::Landmark*> by_name;
  for (const SceneTruth::Landmark& l : truth_landmarks) by_name[l.name] = &l;
  nlohmann::json errors = nlohmann::json::array();
  std::vector<double> error_m;
  for (const PlacedLandmark& p : placed) {
    const auto truth_landmark = by_name.find(p.landmark.name);
    if (truth_landmark == by_name.end() || p.nearest_keyframe < 0) continue;
    const FramePose& kf = keyframes.at(static_cast<size_t>(p.nearest_keyframe));
    const auto truth = truths.find(kf.segment);
    if (truth == truths.end()) continue;
    const Rigid3d* town_from_camera = TruePoseAt(truth->second, kf.timestamp);
    if (town_from_camera == nullptr) continue;
    // The merged map is metric in the world: the landmark in its keyframe's camera, in metres.
    const Eigen::Vector3d in_camera = town_from_map.scale * (kf.world_from_camera.Inverse() * p.map_position);
    const Eigen::Vector3d d = *town_from_camera * in_camera - truth_landmark->second->enu;
    errors.push_back(
        {{"name", p.landmark.name}, {"error_m", d.norm()}, {"horizontal_m", d.head<2>().norm()}});
    error_m.push_back(d.norm());
  }
  if (error_m.empty()) return nullptr;
  return {{"landmarks", error_m.size()},
          {"landmark_error_median_m", Median(error_m)},
          {"landmark_error_max_m", *std::max_element(error_m.begin(), error_m.end())},
          {"landmark_errors", errors}};
}

}  // namespace semslam
