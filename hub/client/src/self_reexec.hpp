// Re-executing this process after its hub was lost (hub_loss.hpp): the same pid,
// executable, arguments and environment, with AFHUB_REATTACH set.
#pragma once

namespace afhub::hub_loss {

// Reads the arguments (/proc/self/cmdline), the environment and the signal mask the
// re-exec will use, into state(). Throws afhub::Error when the arguments are unreadable.
void prepare_self_reexec();

// execve of /proc/self/exe with what prepare_self_reexec() kept: allocates nothing and
// takes no lock, so that any thread may call it while others hold the heap's locks.
// The stop signals (Ctrl-C, SIGTERM, SIGHUP, SIGQUIT) go across blocked: one sent before
// the new image has its handlers stays pending (it ended the process with code 130).
[[noreturn]] void reexecute_self() noexcept;

// In the re-executed image, once its stop handlers are installed: the stop signals
// unblocked, and one that came meanwhile handled.
void unblock_stop_signals() noexcept;

}  // namespace afhub::hub_loss
