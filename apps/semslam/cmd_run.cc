// semslam run: SLAM (and, as they are enabled, semantics, GPS and landmarks) over one sequence; every output
// goes to --out.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "commands.h"
#include "semslam/system/sequence_runner.h"
#include "semslam/system/slam_config.h"

namespace semslam::cli {
namespace {

struct RunArgs {
  std::string sequence;
  std::string out;
  std::string mode = "mono";
  std::string frames;
  std::string config;
  std::string map_in;
  std::string pacing;
  std::string vocabulary;
  bool localization_only = false;
  bool no_loop_closing = false;
  bool quiet = false;
};

void Run(const RunArgs& args) {
  RunOptions options;
  options.sequence = args.sequence;
  options.output = args.out;
  options.slam.mode = args.mode == "stereo" ? SensorMode::kStereo : SensorMode::kMonocular;
  options.slam.tracker.monocular = options.slam.mode == SensorMode::kMonocular;
  if (!args.config.empty()) ApplySlamConfig(args.config, &options.slam);
  if (!args.pacing.empty()) {
    options.slam.pacing = args.pacing == "fast"       ? Pacing::kFast
                          : args.pacing == "realtime" ? Pacing::kRealtime
                                                      : Pacing::kSynchronous;
  }
  if (!args.vocabulary.empty()) options.slam.vocabulary = args.vocabulary;
  if (args.no_loop_closing) options.slam.loop.enabled = false;
  options.slam.localization_only = args.localization_only;
  if (!args.frames.empty()) ParseFrameRange(args.frames, &options.first_frame, &options.end_frame);
  options.map_in = args.map_in;
  options.show_progress = !args.quiet;
  RunSequence(options);
}

}  // namespace

void AddRunCommand(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  auto* cmd = app.add_subcommand("run", "Run SLAM (and semantics, GPS, landmarks) on a sequence");
  cmd->add_option(
         "--sequence", args->sequence,
         "KITTI odometry sequence folder, KITTI raw drive, synthetic city output, or image folder with "
         "camera.yaml")
      ->required();
  cmd->add_option("--out", args->out, "Output folder (created if missing)")->required();
  cmd->add_option("--mode", args->mode, "Sensor mode")
      ->check(CLI::IsMember({"mono", "stereo"}))
      ->capture_default_str();
  cmd->add_option("--frames", args->frames, "Frames A:B (A..B-1; either side may be empty)");
  cmd->add_option("--config", args->config, "YAML file of SLAM options (see config/default.yaml)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--map-in", args->map_in, "Start from this saved map (map.semslam): relocalize first")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--localization-only", args->localization_only,
                "Track against --map-in without changing it (no new keyframes or points)");
  cmd->add_option(
         "--pacing", args->pacing,
         "fast: frames as fast as tracking goes; realtime: at the camera's rate (default); synchronous: "
         "wait for mapping after each keyframe (reproducible)")
      ->check(CLI::IsMember({"fast", "realtime", "synchronous"}));
  cmd->add_option("--vocabulary", args->vocabulary,
                  "Bag-of-words vocabulary (default: data/vocabulary/semslam.voc)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--no-loop-closing", args->no_loop_closing, "Disable loop closing");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress lines");
  cmd->callback([args] { Run(*args); });
}

}  // namespace semslam::cli
