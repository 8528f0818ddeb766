#include "semslam/system/benchmark.h"

#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/core/interrupt.h"
#include "semslam/core/text_reader.h"
#include "semslam/core/timing.h"
#include "semslam/system/run_metadata.h"

extern char** environ;

namespace semslam {
namespace {

double Module(const nlohmann::json& timing, const char* module, const char* field) {
  return timing.contains(module) ? timing[module].value(field, 0.0) : 0.0;
}

void RunProcess(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, args[0], nullptr, nullptr, args.data(), environ) != 0) {
    throw std::runtime_error(fmt::format("cannot start {}", argv[0]));
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  // Ctrl-C reaches the whole process group: the run saved what it did and stopped, and so does the bench.
  if (InterruptRequested()) {
    throw Interrupted(InterruptSignal(), fmt::format("bench: interrupted by {} during `{}`", InterruptName(),
                                                     fmt::join(argv, " ")));
  }
  if (WIFSIGNALED(status)) {
    throw std::runtime_error(fmt::format("`{}` was killed by signal {} ({})", fmt::join(argv, " "),
                                         WTERMSIG(status), strsignal(WTERMSIG(status))));
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw std::runtime_error(
        fmt::format("`{}` failed with exit code {}", fmt::join(argv, " "), WEXITSTATUS(status)));
  }
}

}  // namespace

void BenchOptions::Check() const {
  Require(!executable.empty() && !sequence.empty() && !output.empty(),
          "bench: the executable, --sequence and --out are required");
  Require(repeat >= 1, "bench: --repeat must be >= 1");
}

BenchRun ReadBenchRun(const std::filesystem::path& run_dir) {
  const nlohmann::json run = ReadJsonFile(run_dir / "run.json");
  const nlohmann::json timing = ReadJsonFile(run_dir / "timing.json");
  BenchRun r;
  r.directory = run_dir;
  r.frames = run.value("frames", size_t{0});
  r.tracked = run.value("tracked", size_t{0});
  r.keyframes = run.value("keyframes", size_t{0});
  r.points = run.value("points", size_t{0});
  r.loops = run.value("loops", size_t{0});
  r.ate_rmse = run.value("ate_rmse", -1.0);
  r.peak_rss_mib = run.value("peak_rss_mib", 0.0);
  r.seconds = run.value("seconds", 0.0);
  r.tracking_median_ms = Module(timing, "tracking", "median_ms");
  r.tracking_p95_ms = Module(timing, "tracking", "p95_ms");
  r.tracking_mean_ms = Module(timing, "tracking", "mean_ms");
  r.tracking_max_ms = Module(timing, "tracking", "max_ms");
  r.orb_median_ms = Module(timing, "orb_extraction", "median_ms");
  r.local_ba_median_ms = Module(timing, "local_ba", "median_ms");
  return r;
}

std::vector<MapSizeBucket> TrackingByMapSize(const std::filesystem::path& tracking_csv, int buckets) {
  TextReader reader(tracking_csv);
  std::vector<std::pair<size_t, double>> samples;  // (map points, ms) of tracked frames
  bool header = true;
  while (const auto line = reader.NextLine()) {
    if (header) {
      header = false;
      continue;
    }
    const auto fields = SplitFields(*line, ',');
    if (fields.size() < 6) throw InputError(reader.Where(), "expected at least 6 fields");
    if (fields[1] != "ok") continue;
    samples.emplace_back(static_cast<size_t>(ParseInt(fields[5], reader.Where(), "map_points")),
                         ParseDouble(fields[2], reader.Where(), "tracking_ms"));
  }
  std::sort(samples.begin(), samples.end());
  std::vector<MapSizeBucket> result;
  for (int b = 0; b < buckets && !samples.empty(); ++b) {
    const size_t lo = samples.size() * static_cast<size_t>(b) / static_cast<size_t>(buckets);
    const size_t hi = samples.size() * static_cast<size_t>(b + 1) / static_cast<size_t>(buckets);
    if (lo >= hi) continue;
    std::vector<double> ms;
    for (size_t k = lo; k < hi; ++k) ms.push_back(samples[k].second);
    const TimingSummary summary = Summarize(ms);
    result.push_back(
        {samples[lo].first, samples[hi - 1].first + 1, hi - lo, summary.median_ms, summary.p95_ms});
  }
  return result;
}

BenchResult RunBenchmark(const BenchOptions& options) {
  options.Check();
  BenchResult result;
  for (int i = 1; i <= options.repeat; ++i) {
    const std::filesystem::path dir = options.output / fmt::format("run_{}", i);
    std::vector<std::string> argv = {options.executable.string(),
                                     "run",
                                     "--sequence",
                                     options.sequence.string(),
                                     "--out",
                                     dir.string(),
                                     "--overwrite",  // the benchmark's own folders
                                     "-q"};
    argv.insert(argv.end(), options.run_args.begin(), options.run_args.end());
    RunProcess(argv);
    result.runs.push_back(ReadBenchRun(dir));
  }
  result.tracking_vs_map_size = TrackingByMapSize(options.output / "run_1" / "tracking.csv");
  WriteFileAtomically(options.output / "bench.json", BenchResultJson(result));
  return result;
}

std::string BenchResultJson(const BenchResult& result) {
  nlohmann::json runs = nlohmann::json::array();
  for (const BenchRun& r : result.runs) {
    runs.push_back({{"directory", r.directory.string()},
                    {"frames", r.frames},
                    {"tracked", r.tracked},
                    {"keyframes", r.keyframes},
                    {"points", r.points},
                    {"loops", r.loops},
                    {"ate_rmse", r.ate_rmse},
                    {"tracking_median_ms", r.tracking_median_ms},
                    {"tracking_p95_ms", r.tracking_p95_ms},
                    {"tracking_mean_ms", r.tracking_mean_ms},
                    {"tracking_max_ms", r.tracking_max_ms},
                    {"orb_median_ms", r.orb_median_ms},
                    {"local_ba_median_ms", r.local_ba_median_ms},
                    {"peak_rss_mib", r.peak_rss_mib},
                    {"seconds", r.seconds}});
  }
  nlohmann::json buckets = nlohmann::json::array();
  for (const MapSizeBucket& b : result.tracking_vs_map_size) {
    buckets.push_back({{"min_points", b.min_points},
                       {"max_points", b.max_points},
                       {"frames", b.frames},
                       {"median_ms", b.median_ms},
                       {"p95_ms", b.p95_ms}});
  }
  return nlohmann::json{{"runs", runs}, {"tracking_vs_map_size", buckets}}.dump(2) + "\n";
}

}  // namespace semslam
