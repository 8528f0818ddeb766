// semslam localize: every frame of a sequence relocalized against a saved map without GPS, reported in the
// map it is found in, and, where that map is in the world, in WGS84 and as the nearest landmarks with their
// memberships.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "cli_support.h"
#include "commands.h"
#include "semslam/system/localizer.h"
#include "semslam/system/sequence_runner.h"
#include "semslam/system/slam_config.h"

namespace semslam::cli {
namespace {

struct LocalizeArgs : CameraAndOutputArgs {
  std::string map;
  std::string sequence;
  std::string mode = "mono";
  std::string frames;
  std::string config;
  std::string vocabulary;
  size_t landmarks = 3;  // --nearest-landmarks (a count; `run --landmarks` is a file)
  std::string gps;
  int gps_every = 30;
  bool quiet = false;
};

void Run(const LocalizeArgs& args) {
  LocalizeOptions options;
  options.map = args.map;
  options.sequence = args.sequence;
  options.camera = args.camera;
  options.output = args.out;
  options.slam.mode = ParseSensorMode(args.mode).value();  // CLI11 checked the name
  options.slam.pacing = Pacing::kFast;
  if (!args.config.empty()) ApplySlamConfig(args.config, &options.slam);
  if (!args.vocabulary.empty()) options.slam.vocabulary = args.vocabulary;
  if (!args.frames.empty()) ParseFrameRange(args.frames, &options.first_frame, &options.end_frame);
  options.max_landmarks = args.landmarks;
  options.gps = args.gps;
  options.gps_every = args.gps_every;
  options.show_progress = !args.quiet && !Quiet();
  options.overwrite = args.overwrite;
  options.max_bad_frames_in_row = args.max_bad_frames;
  const LocalizeSummary summary = LocalizeSequence(options);
  std::printf("%zu of %zu frames localized (%zu in the world)", summary.localized, summary.frames,
              summary.in_world);
  if (summary.within_1m >= 0) std::printf(", %.1f %% within 1 m", 100.0 * summary.within_1m);
  if (summary.nearest_landmark_right >= 0) {
    std::printf(", nearest landmark right for %.1f %%", 100.0 * summary.nearest_landmark_right);
  }
  std::printf("\n");
}

}  // namespace

void AddLocalizeCommand(CLI::App& app) {
  auto args = std::make_shared<LocalizeArgs>();
  auto* cmd = app.add_subcommand("localize", "Relocalize a sequence against a saved map without GPS");
  cmd->add_option("--map", args->map, "map.semslam written by semslam run")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--sequence", args->sequence, "Sequence to localize (any folder semslam run reads)")
      ->required();
  AddCameraAndOutputOptions(*cmd, *args);
  cmd->add_option("--mode", args->mode, "Sensor mode")
      ->check(CLI::IsMember({"mono", "stereo"}))
      ->capture_default_str();
  cmd->add_option("--frames", args->frames, "Frames A:B (A..B-1)");
  cmd->add_option("--config", args->config, "YAML file of SLAM options")->check(CLI::ExistingFile);
  cmd->add_option("--vocabulary", args->vocabulary, "Bag-of-words vocabulary")->check(CLI::ExistingFile);
  cmd->add_option("--nearest-landmarks", args->landmarks, "Nearest landmarks reported per frame")
      ->capture_default_str();
  cmd->add_option(
         "--gps", args->gps,
         "GPS log of this session (as `run --gps`): places maps the map file does not put in the world")
      ->check(CLI::ExistingPath);
  cmd->add_option("--gps-every", args->gps_every, "Use one GPS fix every N frames")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", args->quiet, "Only errors on stderr (no log messages, no progress lines)");
  cmd->callback([args] { Run(*args); });
}

}  // namespace semslam::cli
