#include "semslam/system/run_evaluation.h"

#include <spdlog/spdlog.h>

#include <optional>
#include <string>

#include "semslam/eval/trajectory_metrics.h"
#include "semslam/report/geo_evaluation.h"
#include "semslam/semantics/class_table.h"
#include "semslam/sim/scene_file.h"
#include "semslam/system/semantic_evaluation.h"

namespace semslam {

namespace {

nlohmann::json AccuracyJson(const ClassAccuracyCounts& counts) {
  nlohmann::json per_class = nlohmann::json::object();
  for (int c = 0; c < kNumClasses; ++c) {
    const auto n = counts.evaluated[static_cast<size_t>(c)];
    if (n == 0) continue;
    per_class[std::string(ClassKey(c))] = {
        {"evaluated", n},
        {"accuracy", static_cast<double>(counts.correct[static_cast<size_t>(c)]) / static_cast<double>(n)}};
  }
  return {{"accuracy", counts.Accuracy()}, {"evaluated", counts.total_evaluated}, {"per_class", per_class}};
}

// The 3D measure: accuracy on and off class boundaries, and what each true class was labelled as.
nlohmann::json SurfaceJson(const SurfaceScores& e) {
  nlohmann::json confusion = nlohmann::json::object();
  for (int t = 0; t < kNumClasses; ++t) {
    nlohmann::json row = nlohmann::json::object();
    for (int l = 0; l < kNumClasses; ++l) {
      if (const auto n = e.confusion[static_cast<size_t>(t)][static_cast<size_t>(l)])
        row[std::string(ClassKey(l))] = n;
    }
    if (!row.empty()) confusion[std::string(ClassKey(t))] = row;
  }
  nlohmann::json j = AccuracyJson(e.points);
  j["off_boundary"] = AccuracyJson(e.off_boundary);
  j["on_boundary"] = AccuracyJson(e.on_boundary);
  j["labelled_as"] = confusion;
  j["points_unverified"] = e.points_unverified;
  j["points_unlabeled"] = e.points_unlabeled;
  return j;
}

// The ground truth over the frames that were run (path_length_m is the length of the drive that was run, not
// of the whole sequence); nullopt when it has fewer than two poses there.
std::optional<Trajectory> TruthOverFrames(const Trajectory& truth, double first_time, double last_time) {
  constexpr double kSlack = 1e-6;
  Trajectory part;
  for (const StampedPose& pose : truth) {
    if (pose.timestamp >= first_time - kSlack && pose.timestamp <= last_time + kSlack) part.push_back(pose);
  }
  if (part.size() < 2) return std::nullopt;
  return part;
}

}  // namespace

std::optional<AteResult> TrajectoryAgainstTruth(const ImageSequence& sequence, const Trajectory& trajectory,
                                                bool stereo) {
  const auto truth = sequence.GroundTruth();
  if (!truth || trajectory.size() < 3) return std::nullopt;
  try {
    return ComputeAte(trajectory, *truth, stereo ? Alignment::kSe3 : Alignment::kSim3);
  } catch (const EvaluationError& e) {
    spdlog::warn("no accuracy figures: {}", e.what());
    return std::nullopt;
  }
}

double AddLabelFigures(const Map& map, const ImageSequence& sequence, const std::optional<AteResult>& ate,
                       bool stereo, size_t segmented_keyframes, nlohmann::json& run) {
  const auto label_dir = sequence.LabelDirectory();
  if (!label_dir || segmented_keyframes == 0) return -1.0;
  const SemanticEvaluation evaluation = EvaluateSemantics(map, *label_dir);
  double label_accuracy = evaluation.fused.Accuracy();
  run["label_accuracy_2d"] = evaluation.fused.Accuracy();
  run["label_evaluation"] = {{"fused_points", AccuracyJson(evaluation.fused)},
                             {"single_frame_keypoints", AccuracyJson(evaluation.single_frame)},
                             {"points_unlabeled", evaluation.points_unlabeled},
                             {"keyframes", evaluation.keyframes}};
  if (const auto depth_dir = sequence.DepthDirectory(); depth_dir && ate) {
    try {
      const SurfaceEvaluation surface = EvaluateSemantics3d(
          map, {*label_dir, *depth_dir, *sequence.GroundTruth(), ate->truth_from_estimate, stereo});
      label_accuracy = surface.global.points.Accuracy();
      run["label_accuracy_3d"] = surface.per_frame.points.Accuracy();
      run["label_accuracy_3d_global"] = surface.global.points.Accuracy();
      run["label_evaluation"]["surface_points"] = SurfaceJson(surface.per_frame);
      run["label_evaluation"]["surface_points_global_alignment"] = SurfaceJson(surface.global);
      run["label_evaluation"]["surface_keyframes"] = surface.keyframes;
    } catch (const EvaluationError& e) {
      spdlog::warn("no 3D label figures: {}", e.what());
    }
  }
  run["label_accuracy"] = label_accuracy;
  return label_accuracy;
}

double AddTrajectoryFigures(const ImageSequence& sequence, const std::optional<AteResult>& ate,
                            size_t first_frame, size_t last_frame, bool stereo, const GeoOutputs& geo_outputs,
                            const GeoInputs& geo, nlohmann::json& run) {
  if (!ate) return -1.0;
  run["ate_rmse"] = ate->rmse;
  run["ate_alignment"] = stereo ? "se3" : "sim3";
  run["ate_scale"] = ate->scale;
  run["ate_matched"] = ate->matched;
  try {
    if (const auto driven = TruthOverFrames(*sequence.GroundTruth(), sequence.Timestamp(first_frame),
                                            sequence.Timestamp(last_frame))) {
      run["path_length_m"] = PathLength(*driven);
    }
    if (const auto scene = sim::FindSceneJson(sequence.directory()); scene && geo_outputs.georeference) {
      const SceneTruth truth_scene = ReadSceneTruth(scene->parent_path());
      run["geo_evaluation"] = nlohmann::json::parse(EvaluateGeo(geo_outputs, geo, truth_scene).ToJson());
    }
  } catch (const EvaluationError& e) {
    spdlog::warn("no accuracy figures: {}", e.what());
  }
  return ate->rmse;
}

}  // namespace semslam
