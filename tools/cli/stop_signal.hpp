// Clean shutdown on SIGINT and SIGTERM: the handler only sets a flag that loops poll.
#pragma once

namespace jpcr::cli {

/// Installs the handler for SIGINT and SIGTERM (idempotent).
void install_stop_signal_handler();

/// True once SIGINT or SIGTERM arrived.
bool stop_requested();

}  // namespace jpcr::cli
