// The mutable state of a process that outlives its hub (hub_loss.hpp), in one place:
// prepared at the opt-in (survive_hub_loss), then read by the watcher thread, by
// iceoryx's error handler on any thread, and by the re-exec, which must not allocate.
#pragma once

#include <signal.h>
#include <sys/types.h>
#include <time.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include "keepalive_sink.hpp"

namespace afhub::hub_loss {

// What the process before a re-exec tells the next image:
// "COUNT:LOST_HUB:LOST_AT_NS:CARRIED" (CARRIED: carry_into_reattach()'s value).
inline constexpr const char* kReattachVariable = "AFHUB_REATTACH";
// How often a thread waiting on the loss's handling, or for a new hub, looks again.
inline constexpr std::int64_t kReattachPollNs = 10'000'000;

struct State {
  std::atomic<bool> armed{false};     // opted in (survive_hub_loss or notice_hub_loss)
  std::atomic<bool> reexecs{false};   // survive_hub_loss: re-attaches by re-executing
  std::atomic<bool> lost{false};      // hub_lost()
  std::atomic<bool> handling{false};  // one thread handles a loss; the others wait for the exec
  std::atomic<bool> exiting{false};   // the process is exiting on its own: never re-execute it
  std::atomic<std::uint64_t> attached_hub{0};  // the instance of the hub attached to
  std::atomic<pid_t> attached_hub_pid{0};
  // RouDi's socket file (an O_PATH descriptor) when hub_gone() last found the attached
  // hub running: each RouDi makes its socket anew, so while that file is still linked,
  // the hub is the same. Held open, its inode number cannot go to a new file. Never
  // closed (another thread may be looking at it): one per hub confirmed. -1: none yet.
  std::atomic<int> confirmed_socket{-1};
  // notice_hub_loss: this process's socket to RouDi and its runtime's name, once attached
  // (before the watcher starts; read by whichever thread handles the loss).
  RoudiSocket roudi_socket;
  std::string runtime_name;
  // From AFHUB_REATTACH, at the opt-in: 0 at a normal start.
  unsigned reattach_count = 0;
  std::uint64_t lost_hub = 0;   // the instance the previous image lost (0: not an afhub hub)
  std::int64_t lost_at_ns = 0;  // when it was lost (CLOCK_MONOTONIC)
  std::atomic<std::int64_t> carried{0};  // carry_into_reattach(): in, then out again

  std::string who;  // "afhub ctl", in messages
  // What the re-exec needs, prepared at the opt-in so that the loss path itself only
  // formats one variable and calls execve.
  std::vector<std::string> arguments, environment;
  std::vector<char*> argv, envp;  // into the strings above; envp ends in reattach_entry
  char reattach_entry[96] = {};
  sigset_t signal_mask{};

  std::mutex hooks_mutex;
  std::vector<std::function<void()>> hooks;  // on_hub_lost()
};

// Never destroyed: the watcher thread may still look at it while the process exits.
State& state();

inline void sleep_ns(std::int64_t ns) noexcept {
  timespec pause{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
  nanosleep(&pause, nullptr);
}

}  // namespace afhub::hub_loss
