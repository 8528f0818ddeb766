#pragma once
// A run's figures against the truth its sequence carries, for run.json: the trajectory's accuracy (ATE, the
// length driven, and in the synthetic city the geographic outputs against the scene) and the map's labels
// (in 2D at the keypoints, in 3D per keyframe and in one alignment of the whole map).

#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>

#include "semslam/eval/trajectory_metrics.h"
#include "semslam/geometry/trajectory.h"
#include "semslam/io/sequence.h"
#include "semslam/map/map.h"
#include "semslam/report/geo_outputs.h"

namespace semslam {

// The trajectory against the sequence's ground truth (Sim(3) aligned when monocular, SE(3) when stereo);
// nullopt without a truth or with fewer than 3 poses, and with a warning when the two cannot be compared.
std::optional<AteResult> TrajectoryAgainstTruth(const ImageSequence& sequence, const Trajectory& trajectory,
                                                bool stereo);

// Fills run.json's label figures (label_accuracy, label_accuracy_2d, _3d, _3d_global, label_evaluation) when
// the sequence has label images and keyframes were segmented. Returns label_accuracy, the headline (-1 when
// there is none), what a user of the map meets: each point's class against the surface it lies on, with the
// whole map put in the world by the trajectory's one alignment (label_accuracy_3d_global), when the truth has
// depth and `ate`; else the 2D measure (the truth at the point's keypoints).
double AddLabelFigures(const Map& map, const ImageSequence& sequence, const std::optional<AteResult>& ate,
                       bool stereo, size_t segmented_keyframes, nlohmann::json& run);

// Fills run.json's accuracy figures (ate_rmse and its alignment, scale and matches, path_length_m over frames
// first_frame..last_frame, and geo_evaluation in the synthetic city) from `ate`. Returns ate_rmse (-1 without
// `ate`).
double AddTrajectoryFigures(const ImageSequence& sequence, const std::optional<AteResult>& ate,
                            size_t first_frame, size_t last_frame, bool stereo, const GeoOutputs& geo_outputs,
                            const GeoInputs& geo, nlohmann::json& run);

}  // namespace semslam
