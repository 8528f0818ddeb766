// semslam eval --estimate F --truth F|DIR [--camera NAME] [--align sim3|se3|none] [--times FILE]
// [--frames A:B] [--max-dt S]: one JSON object on stdout.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "commands.h"
#include "semslam/eval/trajectory_metrics.h"
#include "semslam/system/sequence_runner.h"

namespace semslam::cli {
namespace {

struct EvalArgs {
  std::string estimate;
  std::string truth;
  std::string camera;
  std::string align = "sim3";
  std::string times;
  std::string frames;
  double max_dt = 0.02;
};

nlohmann::json OrNull(const std::optional<double>& value) {
  return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}

nlohmann::json ToJson(const TrajectoryEvaluation& e, const EvalOptions& options) {
  nlohmann::json j;
  j["alignment"] = std::string(AlignmentName(e.alignment));
  j["alignment_fallback"] = e.ate.alignment_fallback;
  j["estimate_poses"] = e.estimate_poses;
  j["truth_poses"] = e.truth_poses;
  j["matched"] = e.matched;
  j["max_dt"] = options.max_dt;
  j["path_length_m"] = e.path_length_m;
  j["ate_rmse"] = e.ate.rmse;
  j["ate_mean"] = e.ate.mean;
  j["ate_median"] = e.ate.median;
  j["ate_std"] = e.ate.std;
  j["ate_max"] = e.ate.max;
  j["scale"] = e.ate.scale;
  j["rpe_pairs"] = e.rpe ? e.rpe->pairs : 0;
  j["rpe_trans_rmse_m"] = OrNull(e.rpe ? std::optional(e.rpe->trans_rmse_m) : std::nullopt);
  j["rpe_rot_rmse_deg"] = OrNull(e.rpe ? std::optional(e.rpe->rot_rmse_deg) : std::nullopt);
  j["rpe_100m_pairs"] = e.rpe_distance ? e.rpe_distance->pairs : 0;
  j["rpe_100m_trans_rmse_m"] =
      OrNull(e.rpe_distance ? std::optional(e.rpe_distance->trans_rmse_m) : std::nullopt);
  j["rpe_100m_rot_rmse_deg"] =
      OrNull(e.rpe_distance ? std::optional(e.rpe_distance->rot_rmse_deg) : std::nullopt);
  j["kitti_trans_pct"] = OrNull(e.kitti.trans_pct);
  j["kitti_rot_deg_per_100m"] = OrNull(e.kitti.rot_deg_per_100m);
  j["kitti_segment_count"] = e.kitti.segments;
  nlohmann::json segments = nlohmann::json::array();
  for (const KittiSegmentStats& s : e.kitti.per_length) {
    segments.push_back({{"length_m", s.length_m},
                        {"count", s.count},
                        {"trans_pct", s.trans_pct},
                        {"rot_deg_per_100m", s.rot_deg_per_100m}});
  }
  j["kitti_segments"] = segments;
  return j;
}

}  // namespace

void AddEvalCommand(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  auto* cmd =
      app.add_subcommand("eval", "Compare an estimated trajectory with the ground truth (JSON on stdout)");
  cmd->add_option("--estimate", args->estimate, "Estimated trajectory (TUM or KITTI poses)")->required();
  cmd->add_option(
         "--truth", args->truth,
         "Ground-truth trajectory (TUM or KITTI poses), or a sequence folder with a ground truth: a "
         "KITTI odometry sequence with poses/, a KITTI raw drive (its OXTS poses), the synthetic city")
      ->required();
  cmd->add_option("--camera", args->camera,
                  "With a sequence folder as --truth: the camera whose poses are the truth (as semslam run "
                  "--camera; default image_00 / image_0)");
  cmd->add_option("--align", args->align, "Alignment before ATE: sim3 (monocular), se3 (stereo) or none")
      ->check(CLI::IsMember({"sim3", "se3", "none"}))
      ->capture_default_str();
  cmd->add_option("--times", args->times,
                  "Timestamps for KITTI-format files (a times.txt; may list more stamps than poses)");
  cmd->add_option("--frames", args->frames,
                  "Frames A:B that KITTI-format files cover (a run's --frames; line i is frame A+i)");
  cmd->add_option("--max-dt", args->max_dt, "Largest timestamp difference of a matched pair, seconds")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->callback([args] {
    EvalOptions options;
    options.alignment = ParseAlignment(args->align);
    options.max_dt = args->max_dt;
    options.rpe_distance_m = 100.0;  // the rpe_100m_* fields
    const std::optional<std::filesystem::path> times =
        args->times.empty() ? std::nullopt : std::optional<std::filesystem::path>(args->times);
    FrameRange frames;
    if (!args->frames.empty()) {
      size_t end = 0;
      ParseFrameRange(args->frames, &frames.first, &end);
      if (end != std::numeric_limits<size_t>::max()) frames.end = end;
    }
    const TrajectoryEvaluation result =
        EvaluateTrajectoryFiles(args->estimate, args->truth, times, options, frames, args->camera);
    const std::string text = ToJson(result, options).dump(2);
    std::fprintf(stdout, "%s\n", text.c_str());
  });
}

}  // namespace semslam::cli
