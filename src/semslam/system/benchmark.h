#pragma once
// The end-to-end benchmark (`semslam bench`): the same `semslam run` repeated in fresh processes (so that
// each peak memory figure is its own), summarized as tracking time per frame (median, p95), peak RSS, ATE and
// how tracking time grows with the map.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace semslam {

struct BenchOptions {
  std::filesystem::path executable;  // the semslam binary to run
  std::filesystem::path sequence;
  std::filesystem::path output;  // run_1/, run_2/, ... and bench.json go here
  int repeat = 5;
  std::vector<std::string> run_args;  // passed to every `semslam run` (--mode, --frames, --pacing, ...)

  void Check() const;
};

struct BenchRun {
  std::filesystem::path directory;
  size_t frames = 0, tracked = 0, keyframes = 0, points = 0, loops = 0;
  double ate_rmse = -1.0;
  double tracking_median_ms = 0, tracking_p95_ms = 0, tracking_mean_ms = 0, tracking_max_ms = 0;
  double orb_median_ms = 0;
  double local_ba_median_ms = 0;
  double peak_rss_mib = 0;
  double seconds = 0;
};

// Tracking time over frames whose map had points in [min_points, max_points).
struct MapSizeBucket {
  size_t min_points = 0, max_points = 0;
  size_t frames = 0;
  double median_ms = 0, p95_ms = 0;
};

struct BenchResult {
  std::vector<BenchRun> runs;
  std::vector<MapSizeBucket> tracking_vs_map_size;  // of the first run, in quartiles of map size
};

// Runs `executable run --sequence S --out OUT/run_i -q <run_args>` `repeat` times. Throws std::runtime_error
// naming the command when a run fails.
BenchResult RunBenchmark(const BenchOptions& options);
// Reads one finished run's run.json, timing.json and tracking.csv. Throws InputError naming a missing file.
BenchRun ReadBenchRun(const std::filesystem::path& run_dir);
std::vector<MapSizeBucket> TrackingByMapSize(const std::filesystem::path& tracking_csv, int buckets = 4);
std::string BenchResultJson(const BenchResult& result);

}  // namespace semslam
