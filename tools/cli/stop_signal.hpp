// Clean shutdown on SIGINT and SIGTERM: the handler only sets a flag that loops poll. A second
// signal while the first is being handled ends the program at once (the default action), so an
// impatient Ctrl-C still works; one within 1-2 s of the first counts as the same request (Ctrl-C
// under ros2 launch reaches the process twice, from the terminal and from the launcher).
//
// Streaming programs (jpcr_node, jpcr_dds_echo, jpcr_dds_play) stop at the flag and finish
// normally. Batch programs that write an output whole or not at all (jpcr_run, jpcr_curvature,
// jpcr_synth, jpcr_odometry) call throw_if_stopped() once per frame instead: the Interrupted
// exception unwinds their staged outputs, so the output is left as it was, and run_program
// exits with 130 (128 + SIGINT, the shell's convention).
#pragma once

#include <stdexcept>
#include <string>

namespace jpcr::cli {

/// Installs the handler for SIGINT and SIGTERM (idempotent).
void install_stop_signal_handler();

/// True once SIGINT or SIGTERM arrived.
bool stop_requested();

/// A batch run stopped by SIGINT or SIGTERM; run_program prints it and exits 130.
class Interrupted : public std::runtime_error {
 public:
  explicit Interrupted(const std::string& what) : std::runtime_error(what) {}
};

/// Throws Interrupted("stopped by a signal at <where>") once a stop was requested.
void throw_if_stopped(const std::string& where);

}  // namespace jpcr::cli
