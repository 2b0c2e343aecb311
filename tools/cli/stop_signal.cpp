#include "cli/stop_signal.hpp"

#include <csignal>

namespace jpcr::cli {

namespace {

volatile std::sig_atomic_t g_stop = 0;

// Only async-signal-safe calls here: the first signal sets the flag; a second one restores the
// default action and raises the signal again, which ends the process.
extern "C" void on_stop_signal(int signal_number) {
  if (g_stop) {
    struct sigaction fallback {};
    fallback.sa_handler = SIG_DFL;
    sigemptyset(&fallback.sa_mask);
    sigaction(signal_number, &fallback, nullptr);
    raise(signal_number);
    return;
  }
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
