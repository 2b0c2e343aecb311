#include "cli/stop_signal.hpp"

#include <csignal>
#include <ctime>

namespace jpcr::cli {

namespace {

volatile std::sig_atomic_t g_stop = 0;
volatile std::sig_atomic_t g_first_second = 0;  // CLOCK_MONOTONIC seconds of the first signal

// A signal this soon after the first is the same request delivered twice: Ctrl-C under a
// launcher reaches the process from the terminal and from the launcher.
constexpr long kDuplicateSeconds = 2;

long monotonic_seconds() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);  // async-signal-safe (POSIX)
  return static_cast<long>(now.tv_sec);
}

// Only async-signal-safe calls here: the first signal sets the flag; a later one (not a
// duplicate of the first) restores the default action and raises the signal again, which ends
// the process.
extern "C" void on_stop_signal(int signal_number) {
  const long now = monotonic_seconds();
  if (g_stop && now - g_first_second < kDuplicateSeconds) return;
  if (g_stop) {
    struct sigaction fallback {};
    fallback.sa_handler = SIG_DFL;
    sigemptyset(&fallback.sa_mask);
    sigaction(signal_number, &fallback, nullptr);
    raise(signal_number);
    return;
  }
  g_first_second = static_cast<std::sig_atomic_t>(now);
  g_stop = 1;
}

}  // namespace

void install_stop_signal_handler() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool stop_requested() {
  return g_stop != 0;
}

void throw_if_stopped(const std::string& where) {
  if (stop_requested()) throw Interrupted("stopped by a signal at " + where);
}

}  // namespace jpcr::cli
