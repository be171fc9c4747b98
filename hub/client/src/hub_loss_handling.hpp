// What a process that outlives its hub does when the loss is noticed (hub_loss.hpp):
// outputs safe, then the re-exec.
#pragma once

#include <cstdint>

namespace afhub::hub_loss {

enum class LossHandling { kOtherThread, kStopping, kCarriesOn };

// On the first thread to call it: hub_lost() turns true, the on_hub_lost() hooks run,
// the loss is said on stderr with `why`, and the process re-executes, unless it is
// stopping anyway (kStopping) or does not re-execute (kCarriesOn: notice_hub_loss).
// kOtherThread: another thread handles the loss.
LossHandling handle_loss(const char* why) noexcept;

// A thread that meets the loss while another one handles it waits for the exec, or,
// when the process is stopping instead, ends it.
[[noreturn]] void wait_for_reexec() noexcept;

// The hub this process attached to is gone, or is going: its socket refuses, or
// another instance holds the hub lock. (A lock held by none, or unreadable for a
// moment, says nothing: a hub that died also refuses on its socket.)
bool hub_gone() noexcept;

// The running hub's instance, 0 when none (or unreadable).
std::uint64_t hub_instance_now() noexcept;

}  // namespace afhub::hub_loss
