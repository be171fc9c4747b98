// Handling the hub's loss (see hub_loss_handling.hpp).
#include "hub_loss_handling.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <optional>

#include "afhub/hub/hub_presence.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "hub_loss_state.hpp"
#include "keepalive_sink.hpp"
#include "self_reexec.hpp"

namespace afhub::hub_loss {

std::uint64_t hub_instance_now() noexcept {
  try {
    const std::optional<HubIdentity> hub = running_hub();
    return hub ? hub->instance : 0;
  } catch (...) {
    return 0;
  }
}

bool hub_gone() noexcept {
  if (probe_roudi() != RoudiPresence::kRunning) return true;
  const std::uint64_t attached = state().attached_hub, now = hub_instance_now();
  return attached != 0 && now != 0 && now != attached;
}

LossHandling handle_loss(const char* why) noexcept {
  State& s = state();
  if (s.handling.exchange(true)) return LossHandling::kOtherThread;
  s.lost = true;
  char hub[32] = "";
  if (const pid_t pid = s.attached_hub_pid; pid > 0)
    std::snprintf(hub, sizeof hub, " (pid %d)", static_cast<int>(pid));
  {
    std::lock_guard<std::mutex> lock(s.hooks_mutex);
    for (const auto& hook : s.hooks) {
      try {
        hook();
      } catch (...) {
      }
    }
  }
  if (!s.reexecs) {
    std::fprintf(stderr,
                 "%s: the hub%s went away (%s); this process cannot re-attach to another: "
                 "start it again once a hub runs\n",
                 s.who.c_str(), hub, why);
    sink_keepalives(s.roudi_socket, s.runtime_name.c_str());
    return LossHandling::kCarriesOn;
  }
  std::fprintf(stderr,
               "%s: the hub%s went away (%s); outputs made safe, re-attaching when a hub "
               "comes back\n",
               s.who.c_str(), hub, why);
  if (stop_requested() || s.exiting) return LossHandling::kStopping;
  reexecute_self();
}

void wait_for_reexec() noexcept {
  for (;;) {
    sleep_ns(kReattachPollNs);
    if (stop_requested() || state().exiting) _exit(0);
  }
}

}  // namespace afhub::hub_loss
