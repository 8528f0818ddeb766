#include "semslam/core/interrupt.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>

namespace semslam {
namespace {

// Written by the signal handler: lock-free atomics are async-signal-safe.
std::atomic<int> requested_signal{-1};  // -1: no request; 0: a request without a signal
static_assert(std::atomic<int>::is_always_lock_free);

void WriteToStderr(const char* text) {
  const ssize_t ignored = ::write(STDERR_FILENO, text, std::strlen(text));
  (void)ignored;
}

extern "C" void OnInterruptSignal(int signal_number) {
  int expected = -1;
  if (requested_signal.compare_exchange_strong(expected, signal_number)) {
    WriteToStderr(
        "\nsemslam: stopping after the current frame and saving what was done (signal again to quit at "
        "once)\n");
    return;
  }
  // The second signal: quit now. The files being written stay as temporary files, which the next run into
  // the folder removes.
  WriteToStderr("\nsemslam: quitting at once; outputs may be incomplete\n");
  ::_exit(128 + signal_number);
}

}  // namespace

void InstallInterruptHandlers() {
  struct sigaction action {};
  action.sa_handler = OnInterruptSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  ::sigaction(SIGINT, &action, nullptr);
  ::sigaction(SIGTERM, &action, nullptr);
}

bool InterruptRequested() { return requested_signal.load() >= 0; }

int InterruptSignal() { return std::max(requested_signal.load(), 0); }

std::string InterruptName() {
  switch (requested_signal.load()) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "a request";
  }
}

void RequestInterrupt(int signal_number) {
  int expected = -1;
  requested_signal.compare_exchange_strong(expected, signal_number);
}

void ClearInterrupt() { requested_signal.store(-1); }

}  // namespace semslam
