// SIGINT, SIGTERM, SIGHUP and SIGQUIT for long-running processes: a flag their loops poll.
#pragma once

namespace afhub {

void install_stop_signal_handlers();
bool stop_requested();

// One more way to be asked to stop, that stop_requested() looks at too: a Python
// interpreter's Ctrl-C, which only Python's own handler sees. Set once, before any wait.
void set_stop_source(bool (*requested)() noexcept);

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
