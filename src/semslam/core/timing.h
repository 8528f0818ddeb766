#pragma once
// Wall-clock timing of pipeline modules: per-call samples, summarized as median / mean / p95.

#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace semslam {

class Stopwatch {
 public:
  Stopwatch() : start_(Clock::now()) {}
  void Restart() { start_ = Clock::now(); }
  double ElapsedMs() const { return std::chrono::duration<double, std::milli>(Clock::now() - start_).count(); }
  double ElapsedSeconds() const { return ElapsedMs() * 1e-3; }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
};

struct TimingSummary {
  size_t count = 0;
  double median_ms = 0.0;
  double mean_ms = 0.0;
  double p95_ms = 0.0;
  double max_ms = 0.0;
  double total_ms = 0.0;
};

// Summarizes samples (milliseconds). An empty input gives an all-zero summary.
TimingSummary Summarize(std::vector<double> samples_ms);

// Thread-safe collection of named timing samples, e.g. "tracking", "orb_extraction", "local_ba".
class TimingRegistry {
 public:
  void Add(const std::string& module, double milliseconds);
  std::vector<double> Samples(const std::string& module) const;
  std::map<std::string, TimingSummary> SummarizeAll() const;

 private:
  mutable std::mutex mutex_;
  std::map<std::string, std::vector<double>> samples_ms_;
};

// Adds the lifetime of the scope to a registry: { ScopedTimer t(registry, "tracking"); ... }
class ScopedTimer {
 public:
  ScopedTimer(TimingRegistry& registry, std::string module) : registry_(registry), module_(std::move(module)) {}
  ~ScopedTimer() { registry_.Add(module_, watch_.ElapsedMs()); }
  ScopedTimer(const ScopedTimer&) = delete;
  ScopedTimer& operator=(const ScopedTimer&) = delete;

 private:
  TimingRegistry& registry_;
  std::string module_;
  Stopwatch watch_;
};

// Peak resident set size of this process in MiB (from /proc/self/status), 0 if unknown.
double PeakRssMiB();
// Resident set size of this process now, in MiB (from /proc/self/statm), 0 if unknown. Cheap enough per frame.
double CurrentRssMiB();
// Hands memory the allocator keeps after large temporary work (a global bundle adjustment) back to the system,
// so that the process does not stay at its peak. A no-op where the C library has no way to do it.
void ReleaseFreeMemory();

}  // namespace semslam
