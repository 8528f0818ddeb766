#include "semslam/core/progress.h"

#include <fmt/format.h>

#include <cstdio>

namespace semslam {

ProgressReporter::ProgressReporter(std::string label, size_t total, bool enabled, double min_interval_s)
    : label_(std::move(label)), total_(total), enabled_(enabled), min_interval_s_(min_interval_s) {}

void ProgressReporter::Update(size_t done, const std::string& detail) {
  last_done_ = done;
  if (!enabled_) return;
  const double now = since_start_.ElapsedSeconds();
  if (now - last_print_s_ < min_interval_s_) return;
  last_print_s_ = now;
  Print(done, detail);
}

void ProgressReporter::Finish(const std::string& detail) {
  if (enabled_) Print(last_done_, detail);
}

void ProgressReporter::Print(size_t done, const std::string& detail) {
  const double elapsed = since_start_.ElapsedSeconds();
  const double rate = elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
  std::string line;
  if (total_ > 0) {
    const double left = rate > 0 ? static_cast<double>(total_ - std::min(done, total_)) / rate : 0.0;
    line = fmt::format("{}: {}/{} ({:.0f}%), {:.1f}/s, {:.0f} s left", label_, done, total_,
                       100.0 * static_cast<double>(done) / static_cast<double>(total_), rate, left);
  } else {
    line = fmt::format("{}: {} done, {:.1f}/s", label_, done, rate);
  }
  if (!detail.empty()) line += ", " + detail;
  std::fprintf(stderr, "%s\n", line.c_str());
}

}  // namespace semslam
