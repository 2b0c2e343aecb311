#include "cli/stop_signal.hpp"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>

namespace jpcr::cli {

namespace {

volatile std::sig_atomic_t g_stop = 0;  // the first signal's number, 0 before one
// "\nPROGRAM: stopping after the current step (a second signal after 2 s ends it at once)\n",
// made when the handler is installed: the handler may only write(2) it. Its length is the
// handler's to read: 0 while the message is being made.
char g_acknowledgement[256] = "";
volatile std::sig_atomic_t g_acknowledgement_length = 0;
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
  g_stop = signal_number;
  const int saved = errno;  // write(2) may change it under the interrupted code
  [[maybe_unused]] const ssize_t ignored =
      write(STDERR_FILENO, g_acknowledgement, static_cast<std::size_t>(g_acknowledgement_length));
  errno = saved;
}

}  // namespace

void install_stop_signal_handler(OnStop on_stop) {
  g_acknowledgement_length = 0;  // the handler writes nothing while the message is made
  std::atomic_signal_fence(std::memory_order_seq_cst);
  if (on_stop == OnStop::kSayItStops) {
    std::snprintf(g_acknowledgement, sizeof g_acknowledgement,
                  "\n%s: stopping after the current step (a second signal after %ld s ends it "
                  "at once)\n",
                  program_invocation_short_name, kDuplicateSeconds);
    std::atomic_signal_fence(std::memory_order_seq_cst);  // the text before its length
    g_acknowledgement_length = static_cast<std::sig_atomic_t>(std::strlen(g_acknowledgement));
  }
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
  const int signal_number = g_stop;
  if (signal_number == 0) return;
  const char* name = signal_number == SIGINT ? "SIGINT (Ctrl-C)" : "SIGTERM";
  throw Interrupted(std::string("stopped by ") + name + " at " + where, signal_number);
}

}  // namespace jpcr::cli
