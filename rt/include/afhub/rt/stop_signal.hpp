// SIGINT, SIGTERM, SIGHUP and SIGQUIT for long-running processes: a flag their loops poll.
#pragma once

namespace afhub {

void install_stop_signal_handlers();
bool stop_requested();

// One more way to be asked to stop, that stop_requested() looks at too: a Python
// interpreter's Ctrl-C, which only Python's own handler sees. Set once, before any wait.
void set_stop_source(bool (*requested)() noexcept);

// From now on, a stop signal another thread takes is also sent to this thread, for a
// thread about to re-execute the process with the stop signals blocked: the signal
// waits for the new image there, where the flag another thread set goes with the old
// one. The handler sets the flag before it looks whom to send to, so a stop the caller
// does not see in the flag after this call reaches it.
void forward_stop_signals_to_this_thread() noexcept;

// While one lives, a stop signal ends the process at once (exit code 0): for calls
// that block without looking at the flag, such as iceoryx's runtime registering.
class StopEndsBlockingCall {
 public:
  StopEndsBlockingCall();
  ~StopEndsBlockingCall();
  StopEndsBlockingCall(const StopEndsBlockingCall&) = delete;
  StopEndsBlockingCall& operator=(const StopEndsBlockingCall&) = delete;
};

}  // namespace afhub
