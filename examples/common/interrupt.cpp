// SIGINT/SIGTERM handling for the tools (interrupt.h): an async-signal-safe
// flag, set by the handler and read between units of work.

#include "interrupt.h"

#include <atomic>
#include <csignal>

namespace weighted_icp::tools {

namespace {

// Lock-free, so reading and writing it in a signal handler is safe.
std::atomic<int> g_signal{0};
static_assert(std::atomic<int>::is_always_lock_free);

extern "C" void recordSignal(int signal) { g_signal.store(signal); }

}  // namespace

void installInterruptHandlers() {
  for (const int signal : {SIGINT, SIGTERM}) {
    struct sigaction action {};
    action.sa_handler = recordSignal;
    sigemptyset(&action.sa_mask);
    // SA_RESTART: interrupted reads and writes resume rather than fail.
    // SA_RESETHAND: back to the default action, so a second Ctrl-C kills a
    // run that does not stop.
    action.sa_flags = SA_RESTART | SA_RESETHAND;
    sigaction(signal, &action, nullptr);
  }
}

int interruptSignal() { return g_signal.load(); }

std::string signalName(int signal) {
  if (signal == SIGINT) return "SIGINT";
  if (signal == SIGTERM) return "SIGTERM";
  return "signal " + std::to_string(signal);
}

}  // namespace weighted_icp::tools
