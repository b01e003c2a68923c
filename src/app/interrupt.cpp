#include "app/interrupt.hpp"

#include <ostream>
#include <sstream>

namespace bfemp {

namespace {
volatile std::sig_atomic_t g_signal = 0;
struct sigaction g_old_int, g_old_term;

extern "C" void record_signal(int sig) {
  if (g_signal != 0) {  // a second signal: give the default action back and re-raise
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    return;
  }
  g_signal = sig;
}
}  // namespace

InterruptGuard::InterruptGuard() {
  g_signal = 0;
  struct sigaction sa {};
  sa.sa_handler = record_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, &g_old_int);
  sigaction(SIGTERM, &sa, &g_old_term);
}

InterruptGuard::~InterruptGuard() {
  sigaction(SIGINT, &g_old_int, nullptr);
  sigaction(SIGTERM, &g_old_term, nullptr);
}

int pending_signal() { return static_cast<int>(g_signal); }

void stop_after_signal(int sig, long step, double time, const std::string& dir, std::ostream& log,
                       const std::function<void()>& close) {
  try {
    close();
  } catch (const std::exception& e) {
    log << "warning: closing the output after the signal failed: " << e.what() << "\n";
  }
  std::ostringstream msg;
  msg << (sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "signal") << " after step " << step
      << " (t = " << time << " s): frame and checkpoint written; continue with: bfemp restart " << dir;
  throw Interrupted(sig, msg.str());
}

}  // namespace bfemp
