// A thread's priority: lowering it in one thread leaves the others as they were (the global BA yields the
// cores to tracking and local mapping, not the whole process).

#include "semslam/core/thread_priority.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

namespace semslam {
namespace {

struct Lowering {
  int before = 0, after = 0;
  bool lowered = false;
};

// Lowers a fresh worker thread's priority by `steps`: its nice value before and after.
Lowering LowerInAWorker(int steps) {
  Lowering lowering;
  std::thread worker([&] {
    lowering.before = CurrentThreadNiceValue();
    lowering.lowered = LowerCurrentThreadPriority(steps);
    lowering.after = CurrentThreadNiceValue();
  });
  worker.join();
  return lowering;
}

TEST(ThreadPriority, LoweringItInOneThreadLeavesTheOthers) {
  const int caller_before = CurrentThreadNiceValue();
  const Lowering worker = LowerInAWorker(5);
#if defined(__linux__)
  ASSERT_TRUE(worker.lowered) << "raising a nice value needs no privilege";
  EXPECT_EQ(worker.after, std::min(19, worker.before + 5));
#else
  EXPECT_FALSE(worker.lowered);
#endif
  EXPECT_EQ(CurrentThreadNiceValue(), caller_before);
}

TEST(ThreadPriority, NoStepsChangesNothing) {
  const Lowering worker = LowerInAWorker(0);
  EXPECT_TRUE(worker.lowered);
  EXPECT_EQ(worker.after, worker.before);
}

}  // namespace
}  // namespace semslam
