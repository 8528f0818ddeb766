#pragma once
// Realtime pacing: frames are fed no faster than the camera recorded them. A jump in the timestamps (a pause
// in the recording, a 100000 s step, nanoseconds read as seconds) would make the run sleep through it; the
// pacer instead re-anchors its clock at such a frame, warning once, and never sleeps longer than max_gap_s.

#include <optional>

#include "semslam/core/timing.h"

namespace semslam {

struct RealtimePacerOptions {
  // A step between consecutive timestamps larger than this (or backwards) is a gap, not the camera's rate.
  double max_gap_s = 2.0;

  void Check() const;
};

class RealtimePacer {
 public:
  explicit RealtimePacer(const RealtimePacerOptions& options = {});

  // How long to wait before feeding the frame stamped `timestamp` (seconds) so that frames follow their
  // timestamps; 0 when it is due. Re-anchors at a gap. Call once per frame, in order.
  double DelaySeconds(double timestamp);
  // Sleeps for DelaySeconds(timestamp).
  void Wait(double timestamp);
  // After DelaySeconds or Wait for a frame: how much longer it may wait for other work and still be taken
  // within `frame_intervals` of the camera's frame interval after it was due. 0 at the first frame and after
  // a gap (no interval known), and once the frame is that late.
  double SlackSeconds(double frame_intervals) const;

  // How many times the clock was re-anchored at a gap.
  int gaps() const { return gaps_; }

 private:
  RealtimePacerOptions options_;
  std::optional<Stopwatch> clock_;
  double anchor_timestamp_ = 0.0;
  std::optional<double> last_timestamp_;
  double last_interval_s_ = 0.0;  // 0: unknown
  int gaps_ = 0;
};

}  // namespace semslam
