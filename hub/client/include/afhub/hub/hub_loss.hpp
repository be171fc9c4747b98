// Outliving the hub: a process that opts in with survive_hub_loss() makes its outputs
// safe when its hub goes away, waits for a hub to come back and re-attaches to it.
//
// iceoryx 2.0's runtime is a per-process singleton that cannot be re-initialised, so
// the process re-executes itself: the same pid, executable, arguments and environment
// (execve of /proc/self/exe), with AFHUB_REATTACH set. In order:
//   1. The loss is noticed by an iceoryx error handler (a fatal iceoryx error once the
//      hub's memory is gone, as on `afhub hub stop`; a fatal error while the same hub
//      stays up still terminates the process, as before) or by a watcher thread that
//      checks the hub every 20 ms (RouDi's socket refuses, or the hub's identity names
//      another instance or none: a hub SIGKILLed or replaced).
//   2. hub_lost() turns true, so that loops stop writing (a controller stops commanding,
//      the physics stops stepping and publishing), and the hooks given to on_hub_lost()
//      run, in order (a device driver zeroes its force there).
//   3. The process re-executes. Its connect_to_hub() then waits, however long and never
//      starting a hub itself, for a hub other than the one lost, and carries on from
//      there as at start: the physics reloads its world from the model.
// Ctrl-C or SIGTERM while it waits ends it with exit code 0.
#pragma once

#include <functional>
#include <string>

namespace afhub {

// Opts this process in; call once, after install_stop_signal_handlers() and before
// connect_to_hub(). `who` names it in messages ("afhub ctl"). The arguments to
// re-execute with are read from /proc/self/cmdline now.
void survive_hub_loss(const std::string& who);

// Opts in a process that cannot re-execute itself (a Python interpreter, with its
// script's state) to noticing the loss alone: hub_lost() turns true and the hooks run,
// as above, and the process carries on without re-attaching, its calls that need the
// hub refusing (afhub's Python module raises afhub.Error). A fatal iceoryx error after
// the loss (a call that raced with its notice) ends it with a message saying so,
// instead of iceoryx's assertion.
void notice_hub_loss(const std::string& who);

// Runs `make_safe` when the hub is lost, before the re-exec, on the thread that noticed
// the loss (the watcher, or any thread whose iceoryx call failed). It must not use the
// hub's channels, must not throw, and should be quick: it stands between the loss and
// the outputs being safe.
void on_hub_lost(std::function<void()> make_safe);

// True once the hub is lost, until the re-exec (for good with notice_hub_loss): loops
// stop writing. Real-time safe.
bool hub_lost() noexcept;

// 0 at a normal start; after a hub loss, how many times this process re-attached.
unsigned reattach_count() noexcept;

// A value this process hands its next image when it re-attaches (afhub record: when its
// recording began, so that --duration spans the files), and what the image before it
// handed this one (0 at a normal start). Real-time safe.
void carry_into_reattach(std::int64_t value) noexcept;
std::int64_t carried_from_before_reattach() noexcept;

}  // namespace afhub
