// Realtime pacing (system/pacing.h): frames follow their timestamps, but a jump in the timestamps never makes
// the run sleep through it.

#include "semslam/system/pacing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "semslam/core/error.h"

namespace semslam {
namespace {

TEST(RealtimePacer, FollowsTheCameraRate) {
  RealtimePacer pacer;
  EXPECT_EQ(pacer.DelaySeconds(100.0), 0.0);  // the first frame anchors the clock
  const double delay = pacer.DelaySeconds(100.1);
  EXPECT_GT(delay, 0.05);  // 0.1 s after the first, minus the little time since
  EXPECT_LE(delay, 0.1);
  EXPECT_EQ(pacer.gaps(), 0);
}

TEST(RealtimePacer, AJumpOfAHundredThousandSecondsIsNotWaitedFor) {
  RealtimePacer pacer;
  pacer.DelaySeconds(0.0);
  pacer.DelaySeconds(0.1);
  EXPECT_EQ(pacer.DelaySeconds(100000.2), 0.0);
  EXPECT_EQ(pacer.gaps(), 1);
  // After the jump the camera rate applies again, from the new anchor.
  const double delay = pacer.DelaySeconds(100000.3);
  EXPECT_GT(delay, 0.05);
  EXPECT_LE(delay, 0.1);
  EXPECT_EQ(pacer.gaps(), 1);
}

TEST(RealtimePacer, NanosecondTimestampsNeverWaitLongerThanAGap) {
  RealtimePacerOptions options;
  options.max_gap_s = 2.0;
  RealtimePacer pacer(options);
  double worst = 0.0;
  for (int i = 0; i < 50; ++i) worst = std::max(worst, pacer.DelaySeconds(1.3e18 + i * 1e8));  // 10 Hz in ns
  EXPECT_EQ(worst, 0.0);
  EXPECT_EQ(pacer.gaps(), 49);
}

TEST(RealtimePacer, TimeGoingBackIsAGap) {
  RealtimePacer pacer;
  pacer.DelaySeconds(50.0);
  EXPECT_EQ(pacer.DelaySeconds(10.0), 0.0);
  EXPECT_EQ(pacer.gaps(), 1);
}

TEST(RealtimePacer, SlackIsCountedInFrameIntervalsFromWhenTheFrameWasDue) {
  RealtimePacer pacer;
  pacer.DelaySeconds(10.0);
  EXPECT_EQ(pacer.SlackSeconds(1.0), 0.0);   // no frame interval known yet
  ASSERT_GT(pacer.DelaySeconds(11.0), 0.0);  // not due yet: the whole slack is left
  EXPECT_DOUBLE_EQ(pacer.SlackSeconds(1.0), 1.0);
  EXPECT_DOUBLE_EQ(pacer.SlackSeconds(0.5), 0.5);
  EXPECT_EQ(pacer.SlackSeconds(0.0), 0.0);

  RealtimePacer late;
  late.DelaySeconds(10.0);
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(late.DelaySeconds(10.001), 0.0);  // 49 ms late
  EXPECT_EQ(late.SlackSeconds(1.0), 0.0);     // more than one 1 ms interval late: none left
  EXPECT_LE(late.SlackSeconds(100.0), 0.1 - 0.049 + 1e-9);
  EXPECT_EQ(late.DelaySeconds(500.0), 0.0);  // a gap
  EXPECT_EQ(late.SlackSeconds(100.0), 0.0);
}

TEST(RealtimePacer, BadOptionsAreRefused) {
  RealtimePacerOptions options;
  options.max_gap_s = 0.0;
  EXPECT_THROW(RealtimePacer{options}, InvalidArgument);
}

}  // namespace
}  // namespace semslam
