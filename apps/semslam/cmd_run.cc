// semslam run: SLAM (and, as they are enabled, semantics, GPS and landmarks) over one sequence; every output
// goes to --out, the log too (run.log).

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cli_support.h"
#include "commands.h"
#include "semslam/system/sequence_runner.h"
#include "semslam/system/slam_config.h"

namespace semslam::cli {
namespace {

struct RunArgs : CameraAndOutputArgs {
  std::string sequence;
  std::string mode = "mono";
  std::string frames;
  std::string config;
  std::string map_in;
  std::string pacing;
  std::string vocabulary;
  std::string segmenter = "none";
  std::uint64_t seed = 0;
  double camera_height = RoadScaleOptions{}.camera_height_m;
  bool exclude_dynamic = false;
  std::string gps;
  std::string landmarks;
  bool no_gps_fusion = false;
  int gps_every = 30;
  std::vector<double> gps_lever_arm;
  bool localization_only = false;
  bool no_loop_closing = false;
  bool quiet = false;
};

void Run(const RunArgs& args) {
  RunOptions options;
  options.sequence = args.sequence;
  options.camera = args.camera;
  options.output = args.out;
  options.slam.mode = ParseSensorMode(args.mode).value();  // CLI11 checked the name
  if (!args.config.empty()) ApplySlamConfig(args.config, &options.slam);
  if (!args.pacing.empty()) options.slam.pacing = ParsePacing(args.pacing).value();
  if (!args.vocabulary.empty()) options.slam.vocabulary = args.vocabulary;
  if (args.no_loop_closing) options.slam.loop.enabled = false;
  options.slam.localization_only = args.localization_only;
  options.slam.exclude_dynamic = args.exclude_dynamic;
  options.segmenter = args.segmenter;
  options.gps = args.gps;
  options.landmarks = args.landmarks;
  options.gps_fusion = !args.no_gps_fusion;
  options.gps_every = args.gps_every;
  if (!args.gps_lever_arm.empty()) {
    options.gps_antenna_in_camera_m =
        Eigen::Vector3d(args.gps_lever_arm[0], args.gps_lever_arm[1], args.gps_lever_arm[2]);
  }
  options.seed = args.seed;
  options.camera_height_m = args.camera_height;
  if (!args.frames.empty()) ParseFrameRange(args.frames, &options.first_frame, &options.end_frame);
  options.map_in = args.map_in;
  options.show_progress = !args.quiet && !Quiet();
  options.provenance = Provenance();
  options.overwrite = args.overwrite;
  options.max_bad_frames_in_row = args.max_bad_frames;
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
  AddCameraAndOutputOptions(*cmd, *args);
  cmd->add_option("--mode", args->mode, "Sensor mode")
      ->check(CLI::IsMember({"mono", "stereo"}))
      ->capture_default_str();
  cmd->add_option("--frames", args->frames, "Frames A:B (A..B-1; either side may be empty)");
  cmd->add_option("--config", args->config, "YAML file of SLAM options (see config/default.yaml)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--map-in", args->map_in, "Start from this saved map (map.semslam): relocalize first")
      ->check(CLI::ExistingFile);
  cmd->add_option(
         "--segmenter", args->segmenter,
         "Keyframe segmentation: none, espnetv2:FILE.pth or sinet:FILE.pth (Cityscapes state dicts, e.g. "
         "../shared/data/segmentation_weights), enet:FILE (ENet Torch7), onnx:CARD.yaml, labels:DIR (label "
         "or "
         "probability images), truth-noisy:RATE (the synthetic city's labels with noise); optional "
         ",key=value settings (see models/README.md)")
      ->capture_default_str();
  cmd->add_flag(
      "--exclude-dynamic", args->exclude_dynamic,
      "Keep points on persons, riders and vehicles out of tracking and relocalization (needs a segmenter)");
  cmd->add_option(
         "--gps", args->gps,
         "GPS log: KITTI oxts folder, CSV (t,lat,lon[,alt,sigma]), NMEA or KML file (a KML track without "
         "times: one position per frame)")
      ->check(CLI::ExistingPath);
  cmd->add_option("--gps-lever-arm", args->gps_lever_arm,
                  "Where the GPS antenna is in the camera frame, X,Y,Z metres (x right, y down, z forward); "
                  "default: from a KITTI raw drive's calibration, else at the camera")
      ->delimiter(',')
      ->expected(3)
      ->check(CLI::Number);
  cmd->add_option("--landmarks", args->landmarks,
                  "Landmark catalogue: CSV (name,lat,lon[,alt,category]), GeoJSON or .osm/.osm.pbf")
      ->check(CLI::ExistingFile);
  cmd->add_option("--gps-every", args->gps_every,
                  "Use one GPS fix every N frames to tie the map to the world (the paper: 30)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag(
      "--no-gps-fusion", args->no_gps_fusion,
      "Tie the map to GPS with one robust similarity (the paper's method) instead of the pose-graph fusion");
  cmd->add_option("--seed", args->seed, "Seed of noisy segmenters")->capture_default_str();
  cmd->add_option(
         "--camera-height", args->camera_height,
         "The camera's height above the road, metres: a monocular run without --gps scales its objects "
         "by it (needs a segmenter)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--localization-only", args->localization_only,
                "Track against --map-in without changing it (no new keyframes or points)");
  cmd->add_option(
         "--pacing", args->pacing,
         "fast: frames as fast as tracking goes; realtime: at the camera's rate (default); synchronous: "
         "wait for mapping after each keyframe and for loop corrections (reproducible)")
      ->check(CLI::IsMember({"fast", "realtime", "synchronous"}));
  cmd->add_option("--vocabulary", args->vocabulary,
                  "Bag-of-words vocabulary (default: data/vocabulary/semslam.voc)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--no-loop-closing", args->no_loop_closing, "Disable loop closing");
  cmd->add_flag("-q,--quiet", args->quiet, "Only errors on stderr (no log messages, no progress lines)");
  cmd->callback([args, cmd] {
    if (args->gps.empty()) {
      for (const char* flag : {"--gps-every", "--gps-lever-arm", "--no-gps-fusion"}) {
        if (cmd->count(flag) > 0) spdlog::warn("{} has no effect without --gps", flag);
      }
    }
    Run(*args);
  });
}

}  // namespace semslam::cli
