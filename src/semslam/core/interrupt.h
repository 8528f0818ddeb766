#pragma once
// Ctrl-C and SIGTERM: the first one asks long runs to stop cleanly (finish the current frame, save what was
// done); a second one ends the process at once. Loops poll InterruptRequested().

#include <stdexcept>
#include <string>

namespace semslam {

// Installs the SIGINT and SIGTERM handlers (the CLI does, once, at start).
void InstallInterruptHandlers();

// Whether a stop was asked for (by a signal or RequestInterrupt).
bool InterruptRequested();
// The signal that asked for it (SIGINT, SIGTERM), or 0.
int InterruptSignal();
// "SIGINT", "SIGTERM", or "a request" when no signal asked.
std::string InterruptName();
// Asks for a stop as the first signal would (tests; a caller that wants a run to end early).
void RequestInterrupt(int signal_number = 0);
// Forgets an earlier request (tests).
void ClearInterrupt();

// Thrown after a run stopped at an interruption and saved its outputs: the CLI exits with 128 + signal.
class Interrupted : public std::runtime_error {
 public:
  Interrupted(int signal_number, const std::string& message)
      : std::runtime_error(message), signal_number_(signal_number) {}
  int signal_number() const { return signal_number_; }
  int ExitCode() const { return 128 + (signal_number_ > 0 ? signal_number_ : 2); }

 private:
  int signal_number_;
};

}  // namespace semslam
