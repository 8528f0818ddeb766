#include "semslam/system/pacing.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "semslam/core/error.h"

namespace semslam {

void RealtimePacerOptions::Check() const {
  Require(std::isfinite(max_gap_s) && max_gap_s > 0, "realtime pacing: max_gap_s must be positive");
}

RealtimePacer::RealtimePacer(const RealtimePacerOptions& options) : options_(options) { options_.Check(); }

double RealtimePacer::DelaySeconds(double timestamp) {
  const bool gap = last_timestamp_ && !(std::abs(timestamp - *last_timestamp_) <= options_.max_gap_s &&
                                        timestamp >= *last_timestamp_);
  if (gap) {
    if (gaps_ == 0) {
      spdlog::warn(
          "realtime pacing: the timestamps jump from {:.9g} to {:.9g} s (more than {} s; a pause in the "
          "recording, or timestamps not in seconds?): the clock is re-anchored at such jumps instead of "
          "waiting (this is reported once)",
          *last_timestamp_, timestamp, options_.max_gap_s);
    }
    ++gaps_;
  }
  last_interval_s_ = last_timestamp_ && !gap ? timestamp - *last_timestamp_ : 0.0;
  last_timestamp_ = timestamp;
  if (!clock_ || gap) {
    clock_.emplace();
    anchor_timestamp_ = timestamp;
    return 0.0;
  }
  const double wait_s = (timestamp - anchor_timestamp_) - clock_->ElapsedSeconds();
  if (wait_s <= 0) return 0.0;
  // Between frames no more than a gap's worth, whatever the clock says.
  return std::min(wait_s, options_.max_gap_s);
}

double RealtimePacer::SlackSeconds(double frame_intervals) const {
  if (!clock_ || !last_timestamp_ || !(last_interval_s_ > 0) || !(frame_intervals > 0)) return 0.0;
  const double late_s = clock_->ElapsedSeconds() - (*last_timestamp_ - anchor_timestamp_);
  return std::max(0.0, frame_intervals * last_interval_s_ - std::max(0.0, late_s));
}

void RealtimePacer::Wait(double timestamp) {
  const double delay_s = DelaySeconds(timestamp);
  if (delay_s > 0) std::this_thread::sleep_for(std::chrono::duration<double>(delay_s));
}

}  // namespace semslam
