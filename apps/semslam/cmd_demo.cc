// semslam demo: the whole pipeline on the built-in synthetic city (see system/demo.h for what it writes).

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "cli_support.h"
#include "commands.h"
#include "semslam/core/log_file.h"
#include "semslam/system/demo.h"

namespace semslam::cli {
namespace {

struct DemoArgs {
  std::string out = "out/demo";
  int frames = 1200;
  int second_drive = 300;
  std::uint64_t seed = 1;
  std::string mode = "mono";
  std::string pacing = "realtime";
  std::string segmenter = "truth-noisy:0.25";
  bool quiet = false;
};

void Run(const DemoArgs& args) {
  DemoOptions options;
  options.output = args.out;
  options.frames = args.frames;
  options.second_drive_frames = args.second_drive;
  options.seed = args.seed;
  options.mode = args.mode;
  options.pacing = ParsePacing(args.pacing).value();  // CLI11 checked the name
  options.segmenter = args.segmenter;
  options.show_progress = !args.quiet && !Quiet();
  options.provenance = Provenance();
  options.Check();  // before anything is written
  std::filesystem::create_directories(options.output);
  const LogFile log(options.output / "demo.log", LogHeader());
  const DemoSummary s = RunDemo(options);
  std::printf("demo written to %s (%.0f s)\n", args.out.c_str(), s.seconds);
  std::printf("  trajectory ATE %.3f m over %.0f m (%.3f %%)\n", s.ate_rmse, s.path_length_m,
              s.path_length_m > 0 ? 100.0 * s.ate_rmse / s.path_length_m : 0.0);
  if (s.label_accuracy >= 0) std::printf("  map-point labels %.1f %% right\n", 100.0 * s.label_accuracy);
  if (s.localized_within_1m >= 0) {
    std::printf(
        "  second drive without GPS: %.1f %% of frames within 1 m, nearest landmark right for %.1f %%\n",
        100.0 * s.localized_within_1m, 100.0 * s.nearest_landmark_right);
  }
  if (!s.route_from.empty()) {
    std::printf("  route %s -> %s: %.0f m (route.geojson)\n", s.route_from.c_str(), s.route_to.c_str(),
                s.route_length_m);
  }
  std::printf("  open %s/run/report.html\n", args.out.c_str());
}

}  // namespace

void AddDemoCommand(CLI::App& app) {
  auto args = std::make_shared<DemoArgs>();
  auto* cmd = app.add_subcommand(
      "demo", "Run the whole pipeline on the built-in synthetic city and write every output");
  cmd->add_option("--out", args->out, "Output folder")->capture_default_str();
  cmd->add_option("--frames", args->frames, "Frames of the main drive")->capture_default_str();
  cmd->add_option("--second-drive", args->second_drive,
                  "Frames of the second drive (localization without GPS)")
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "Town and route")->capture_default_str();
  cmd->add_option("--mode", args->mode, "Sensor mode")
      ->check(CLI::IsMember({"mono", "stereo"}))
      ->capture_default_str();
  cmd->add_option("--pacing", args->pacing, "fast, realtime or synchronous")
      ->check(CLI::IsMember({"fast", "realtime", "synchronous"}))
      ->capture_default_str();
  cmd->add_option("--segmenter", args->segmenter, "Keyframe segmentation (see semslam run --help)")
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", args->quiet, "Only errors on stderr (no log messages, no progress lines)");
  cmd->callback([args] { Run(*args); });
}

}  // namespace semslam::cli
