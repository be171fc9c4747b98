// The stop flag (see stop_signal.hpp).
#include "afhub/rt/stop_signal.hpp"

#include <signal.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>

namespace afhub {
namespace {
std::atomic<bool> g_stop{false};
std::atomic<int> g_blocking_calls{0};
std::atomic<bool (*)() noexcept> g_stop_source{nullptr};
std::atomic<pid_t> g_forward_to{0};
extern "C" void on_stop_signal(int signal) {
  g_stop = true;  // before the look at g_forward_to: see forward_stop_signals_to_this_thread
  const pid_t to = g_forward_to;
  if (to != 0 && to != static_cast<pid_t>(syscall(SYS_gettid)))
    syscall(SYS_tgkill, getpid(), to, signal);
  if (g_blocking_calls > 0) _exit(0);  // stuck in a call that never looks at the flag
}
}  // namespace

void install_stop_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  // A closed terminal (SIGHUP) and Ctrl-\ (SIGQUIT) stop as Ctrl-C does: their default
  // actions end the process on the spot, with a device's force still applied.
  for (const int signal : {SIGINT, SIGTERM, SIGHUP, SIGQUIT}) sigaction(signal, &action, nullptr);
}

bool stop_requested() {
  if (g_stop) return true;
  bool (*const source)() noexcept = g_stop_source;
  return source && source();
}

void forward_stop_signals_to_this_thread() noexcept {
  g_forward_to = static_cast<pid_t>(syscall(SYS_gettid));
}

void set_stop_source(bool (*requested)() noexcept) {
  g_stop_source = requested;
}

StopEndsBlockingCall::StopEndsBlockingCall() {
  if (g_stop) _exit(0);
  ++g_blocking_calls;
}

StopEndsBlockingCall::~StopEndsBlockingCall() {
  --g_blocking_calls;
}

}  // namespace afhub
