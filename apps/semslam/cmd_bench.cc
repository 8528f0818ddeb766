// semslam bench: `semslam run` repeated in fresh processes; tracking time per frame (median, p95), peak RSS,
// ATE per run, and tracking time against map size. Arguments after `--` go to every run.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "semslam/system/benchmark.h"

namespace semslam::cli {
namespace {

struct BenchArgs {
  std::string sequence;
  std::string camera;
  std::string out;
  int repeat = 5;
  std::vector<std::string> run_args;
};

void Run(const BenchArgs& args) {
  BenchOptions options;
  options.executable = std::filesystem::read_symlink("/proc/self/exe");
  options.sequence = args.sequence;
  options.output = args.out;
  options.repeat = args.repeat;
  options.run_args = args.run_args;
  if (!args.camera.empty()) options.run_args.insert(options.run_args.begin(), {"--camera", args.camera});
  const BenchResult result = RunBenchmark(options);
  std::printf("%-4s %8s %8s %10s %9s %9s %9s %9s %9s\n", "run", "tracked", "ATE[m]", "track_med", "track_p95",
              "orb_med", "lba_med", "RSS[MiB]", "time[s]");
  for (size_t i = 0; i < result.runs.size(); ++i) {
    const BenchRun& r = result.runs[i];
    std::printf("%-4zu %4zu/%-4zu %8.3f %10.2f %9.2f %9.2f %9.1f %9.1f %9.1f\n", i + 1, r.tracked, r.frames,
                r.ate_rmse, r.tracking_median_ms, r.tracking_p95_ms, r.orb_median_ms, r.local_ba_median_ms,
                r.peak_rss_mib, r.seconds);
  }
  std::printf("tracking time against map size (run 1):\n");
  for (const MapSizeBucket& b : result.tracking_vs_map_size) {
    std::printf("  %7zu..%-7zu points: %5zu frames, median %.2f ms, p95 %.2f ms\n", b.min_points,
                b.max_points, b.frames, b.median_ms, b.p95_ms);
  }
  std::printf("written: %s\n", (std::filesystem::path(args.out) / "bench.json").c_str());
}

}  // namespace

void AddBenchCommand(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  auto* cmd = app.add_subcommand(
      "bench",
      "Measure speed and memory end to end: semslam run repeated (arguments after -- go to every run)");
  cmd->add_option("--sequence", args->sequence, "Sequence folder")->required();
  cmd->add_option("--camera", args->camera,
                  "Camera of a KITTI folder, passed to every run (see semslam run)");
  cmd->add_option("--out", args->out, "Output folder (run_1/ ... and bench.json)")->required();
  cmd->add_option("--repeat", args->repeat, "Runs")->capture_default_str()->check(CLI::Range(1, 1000));
  cmd->add_option("run_args", args->run_args, "Arguments for semslam run, after --");
  cmd->callback([args] { Run(*args); });
}

}  // namespace semslam::cli
