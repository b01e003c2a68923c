#pragma once
// Safe interruption of a run: while an InterruptGuard lives, SIGINT and SIGTERM
// only record the signal (async-signal-safe); the run loop polls
// pending_signal() after each completed step, writes a frame and a checkpoint,
// closes its files and throws Interrupted. A second signal (either kind) while
// one is pending restores the default action (a user pressing Ctrl-C
// twice wants out now). The previous handlers come back when the guard dies.
#include <csignal>
#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>

namespace bfemp {

class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
};

// The signal received since the guard was installed (SIGINT / SIGTERM), or 0.
int pending_signal();

// Thrown by the run loop after it has written the frame and the checkpoint.
struct Interrupted : std::runtime_error {
  Interrupted(int sig, const std::string& msg) : std::runtime_error(msg), signal(sig) {}
  int signal;
  int exit_code() const { return 128 + signal; }  // 130 SIGINT, 143 SIGTERM
};

// The run loop's exit after a signal, once the frame and the checkpoint of
// `step` (at `time` s) are written: calls `close` (the output files; a failure
// is a warning on `log`), then throws Interrupted naming the signal, the step
// and the restart command for `dir`.
[[noreturn]] void stop_after_signal(int sig, long step, double time, const std::string& dir, std::ostream& log,
                                    const std::function<void()>& close);

}  // namespace bfemp
