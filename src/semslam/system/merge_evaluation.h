#pragma once
// How a merged map's landmarks lie against the synthetic city's truth (`semslam merge`,
// system/session_merge.h).
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <vector>

#include "semslam/geo/frame_position.h"
#include "semslam/geometry/sim3.h"
#include "semslam/geometry/trajectory.h"
#include "semslam/landmarks/landmark_map.h"
#include "semslam/report/geo_evaluation.h"

namespace semslam {

// Each landmark placed in the merged map, measured as a run's geo evaluation measures it
// (report/geo_evaluation.h): seen from its nearest keyframe, through that keyframe's true pose, against where
// the landmark truly is. Here the nearest keyframe may be any drive's: `keyframes` carry the drive in their
// `segment`, `truths` each drive's true poses in the town's ENU frame (by segment), and `town_from_map` takes
// the merged map (metric, in the world) into that frame. Landmarks whose keyframe has no truth are left out.
// Returns {"landmarks", "landmark_error_median_m", "landmark_error_max_m", "landmark_errors": [{name,
// error_m, horizontal_m}]}, or null when none could be measured.
nlohmann::json EvaluateMergedLandmarks(const std::vector<PlacedLandmark>& placed,
                                       const std::vector<FramePose>& keyframes,
                                       const std::map<std::uint32_t, Trajectory>& truths,
                                       const Sim3d& town_from_map,
                                       const std::vector<SceneTruth::Landmark>& truth_landmarks);

}  // namespace semslam
