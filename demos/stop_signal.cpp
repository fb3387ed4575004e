#include "stop_signal.hpp"

#include <csignal>

namespace drench {

namespace {

std::atomic<bool> g_stop{false};
volatile std::sig_atomic_t g_signal = 0;

static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler may only touch lock-free atomics");

extern "C" void on_stop_signal(int signal) {
  if (g_signal != 0) {
    // The second signal: the default action (termination) once this handler returns and unblocks it.
    struct sigaction default_action {};
    default_action.sa_handler = SIG_DFL;
    sigemptyset(&default_action.sa_mask);
    sigaction(signal, &default_action, nullptr);
    raise(signal);
    return;
  }
  g_signal = signal;
  g_stop.store(true);
}

}  // namespace

const std::atomic<bool>& stop_requested() {
  return g_stop;
}

void install_stop_handler(bool restart_system_calls) {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  // Either signal blocks the other while the handler runs, so that two at once still count as two.
  sigaddset(&action.sa_mask, SIGINT);
  sigaddset(&action.sa_mask, SIGTERM);
  action.sa_flags = restart_system_calls ? SA_RESTART : 0;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

int stop_signal() {
  return g_signal;
}

int stopped_exit_status() {
  return 128 + (g_signal != 0 ? static_cast<int>(g_signal) : SIGINT);
}

}  // namespace drench
