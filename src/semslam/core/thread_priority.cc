#include "semslam/core/thread_priority.h"

#include <algorithm>
#include <cerrno>

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace semslam {

#if defined(__linux__)
namespace {

// On Linux a nice value belongs to a thread, addressed by its kernel thread id.
id_t CurrentThreadId() { return static_cast<id_t>(syscall(SYS_gettid)); }

}  // namespace

int CurrentThreadNiceValue() {
  errno = 0;
  const int nice = getpriority(PRIO_PROCESS, CurrentThreadId());
  return errno == 0 ? nice : 0;
}

bool LowerCurrentThreadPriority(int steps) {
  if (steps <= 0) return steps == 0;
  const id_t thread = CurrentThreadId();
  errno = 0;
  const int nice = getpriority(PRIO_PROCESS, thread);
  if (errno != 0) return false;
  return setpriority(PRIO_PROCESS, thread, std::min(19, nice + steps)) == 0;
}
#else
int CurrentThreadNiceValue() { return 0; }
bool LowerCurrentThreadPriority(int) { return false; }
#endif

}  // namespace semslam
