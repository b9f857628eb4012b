#pragma once
// Stopping a long run cleanly on Ctrl-C (SIGINT) or SIGTERM: the handler only
// sets a flag; the tool checks it between frames or runs, joins its threads,
// finishes or discards its outputs, says which, and exits 128 + the signal.

#include <string>

namespace weighted_icp::tools {

/// @brief Installs handlers for SIGINT and SIGTERM that record the signal;
/// a second signal ends the process at once (the default action), for a run
/// stuck where the flag is not checked.
void installInterruptHandlers();

/// @brief The signal received since installInterruptHandlers(), 0 if none.
int interruptSignal();

/// @brief True once SIGINT or SIGTERM has been received.
inline bool interrupted() { return interruptSignal() != 0; }

/// @brief "SIGINT", "SIGTERM" or "signal N".
/// @param signal a signal number
std::string signalName(int signal);

/// @brief The exit code of a run stopped by `signal`: 128 + signal, as a shell
/// reports a process killed by it (130 for SIGINT, 143 for SIGTERM).
/// @param signal a signal number
inline int interruptExitCode(int signal) { return 128 + signal; }

}  // namespace weighted_icp::tools
