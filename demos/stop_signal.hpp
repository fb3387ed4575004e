#pragma once
/// SIGINT and SIGTERM as a request to stop: the first sets a flag that the long commands (run, reconstruct,
/// sweep) check between steps, so they end with their files whole and say so; a second one ends the process
/// at once (the default action), for a user who does not want to wait for the step under way.

#include <atomic>

namespace drench {

/// The flag the handler sets; what RunOptions::stop and ReconstructOptions::stop point to.
const std::atomic<bool>& stop_requested();

/// Installs the handler for SIGINT and SIGTERM. The handler is async-signal-safe: it only sets the flag
/// (and, on a second signal, restores the default action and raises the signal again).
/// @param restart_system_calls  false for a command that waits in waitpid and must wake up (sweep)
void install_stop_handler(bool restart_system_calls);

/// The signal that asked to stop (SIGINT or SIGTERM), 0 when none has.
int stop_signal();

/// The exit status of a command that a stop signal ended: 128 + the signal, as a shell reports it (130 for
/// SIGINT, 143 for SIGTERM).
int stopped_exit_status();

}  // namespace drench
