#include "semslam/core/interrupt.h"

#include <gtest/gtest.h>
#include <signal.h>

namespace semslam {
namespace {

TEST(Interrupt, RequestAndClear) {
  ClearInterrupt();
  EXPECT_FALSE(InterruptRequested());
  RequestInterrupt();
  EXPECT_TRUE(InterruptRequested());
  EXPECT_EQ(InterruptSignal(), 0);
  RequestInterrupt(SIGTERM);  // the first request stays
  EXPECT_EQ(InterruptSignal(), 0);
  ClearInterrupt();
  EXPECT_FALSE(InterruptRequested());
}

TEST(Interrupt, TheFirstSignalIsRecordedNotFatal) {
  ClearInterrupt();
  InstallInterruptHandlers();
  ASSERT_EQ(::raise(SIGINT), 0);  // the process goes on
  EXPECT_TRUE(InterruptRequested());
  EXPECT_EQ(InterruptSignal(), SIGINT);
  EXPECT_EQ(InterruptName(), "SIGINT");
  EXPECT_EQ(Interrupted(SIGINT, "x").ExitCode(), 130);
  EXPECT_EQ(Interrupted(SIGTERM, "x").ExitCode(), 143);
  ClearInterrupt();
  signal(SIGINT, SIG_DFL);
  signal(SIGTERM, SIG_DFL);
}

TEST(InterruptDeathTest, ASecondSignalQuitsAtOnce) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        ClearInterrupt();
        InstallInterruptHandlers();
        ::raise(SIGTERM);
        ::raise(SIGTERM);
        std::exit(0);  // not reached
      },
      ::testing::ExitedWithCode(128 + SIGTERM), "quitting at once");
}

}  // namespace
}  // namespace semslam
