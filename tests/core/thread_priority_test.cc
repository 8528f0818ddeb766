// A thread's priority: lowering it in one thread leaves the others as they were (the global BA yields the
// cores to tracking and local mapping, not the whole process).

#include "semslam/core/thread_priority.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

namespace semslam {
namespace {

TEST(ThreadPriority, LoweringItInOneThreadLeavesTheOthers) {
  const int caller_before = CurrentThreadNiceValue();
  int worker_before = 0, worker_after = 0;
  bool lowered = false;
  std::thread worker([&] {
    worker_before = CurrentThreadNiceValue();
    lowered = LowerCurrentThreadPriority(5);
    worker_after = CurrentThreadNiceValue();
  });
  worker.join();
#if defined(__linux__)
  ASSERT_TRUE(lowered) << "raising a nice value needs no privilege";
  EXPECT_EQ(worker_after, std::min(19, worker_before + 5));
#else
  EXPECT_FALSE(lowered);
#endif
  EXPECT_EQ(CurrentThreadNiceValue(), caller_before);
}

TEST(ThreadPriority, NoStepsChangesNothing) {
  int before = 0, after = 0;
  bool lowered = false;
  std::thread worker([&] {
    before = CurrentThreadNiceValue();
    lowered = LowerCurrentThreadPriority(0);
    after = CurrentThreadNiceValue();
  });
  worker.join();
  EXPECT_TRUE(lowered);
  EXPECT_EQ(after, before);
}

}  // namespace
}  // namespace semslam
