#pragma once
// Progress of long runs on stderr: at most a few lines per second, with rate and time left.

#include <cstddef>
#include <string>

#include "semslam/core/timing.h"

namespace semslam {

class ProgressReporter {
 public:
  // total == 0 means unknown. Prints nothing when `enabled` is false.
  ProgressReporter(std::string label, size_t total, bool enabled = true, double min_interval_s = 2.0);

  // Reports that `done` items are complete; `detail` is appended (e.g. "tracked 120, 14 keyframes").
  void Update(size_t done, const std::string& detail = {});
  // Prints the final line (always, if enabled).
  void Finish(const std::string& detail = {});

 private:
  void Print(size_t done, const std::string& detail);

  std::string label_;
  size_t total_;
  bool enabled_;
  double min_interval_s_;
  Stopwatch since_start_;
  double last_print_s_ = -1e9;
  size_t last_done_ = 0;
};

}  // namespace semslam
