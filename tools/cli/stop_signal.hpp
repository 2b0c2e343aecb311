// Clean shutdown on SIGINT and SIGTERM: the handler only sets a flag that loops poll. A second
// signal while the first is being handled ends the program at once (the default action), so an
// impatient Ctrl-C still works; one within 1-2 s of the first counts as the same request (Ctrl-C
// under ros2 launch reaches the process twice, from the terminal and from the launcher).
//
// Streaming programs (jpcr_node, jpcr_dds_echo, jpcr_dds_play) stop at the flag and finish
// normally. Batch programs that write an output whole or not at all (jpcr_run, jpcr_curvature,
// jpcr_synth, jpcr_odometry) call throw_if_stopped() once per frame instead: the Interrupted
// exception unwinds their staged outputs, so the output is left as it was, and run_program
// exits with 128 + the signal's number (130 for SIGINT, 143 for SIGTERM: the shell's convention).
// The first signal is acknowledged at once on stderr, since the current frame (a J-full window)
// can take seconds.
#pragma once

#include <stdexcept>
#include <string>

namespace jpcr::cli {

/// Whether the first signal is acknowledged on stderr at once ("PROGRAM: stopping after the
/// current step ..."): batch programs, whose current step can take seconds, say so; streaming
/// ones stop at once and keep stderr for their own lines.
enum class OnStop { kQuiet, kSayItStops };

/// Installs the handler for SIGINT and SIGTERM (idempotent). Batch programs install it before
/// they create their staging directory, so that a signal then still unwinds it.
void install_stop_signal_handler(OnStop on_stop = OnStop::kQuiet);

/// True once SIGINT or SIGTERM arrived.
bool stop_requested();

/// A batch run stopped by SIGINT or SIGTERM; run_program prints it and exits 128 + signal.
class Interrupted : public std::runtime_error {
 public:
  Interrupted(const std::string& what, int signal_number)
      : std::runtime_error(what), signal_number_(signal_number) {}
  int exit_status() const { return 128 + signal_number_; }

 private:
  int signal_number_;
};

/// Throws Interrupted("stopped by SIGINT at <where>") once a stop was requested.
void throw_if_stopped(const std::string& where);

}  // namespace jpcr::cli
