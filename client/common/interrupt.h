// Ctrl-C for commands that hold a server resource (`vpm play` holds the
// session it opened): the first SIGINT or SIGTERM only sets a flag, which
// the command polls to stop, close what it opened and exit; a second one
// ends the process at once (the default action is restored).
#pragma once

#include <chrono>

namespace vpm::cli {

// Installs the handlers for SIGINT and SIGTERM (once per process).
void CatchInterrupts();

// True once SIGINT or SIGTERM arrived after CatchInterrupts().
bool Interrupted();

// Sleeps for `duration`, waking early (within 20 ms) on an interrupt.
// Returns false when interrupted.
bool SleepUnlessInterrupted(std::chrono::microseconds duration);

}  // namespace vpm::cli
