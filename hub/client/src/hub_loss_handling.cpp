// Handling the hub's loss (see hub_loss_handling.hpp).
#include "hub_loss_handling.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <optional>

#include "afhub/hub/hub_presence.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "hub_loss_state.hpp"
#include "keepalive_sink.hpp"
#include "roudi_socket.hpp"
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
  // The hub's lock and identity take some twenty system calls (110 us on the project's
  // VM, every 20 ms in every process); the confirmed socket file, one.
  State& s = state();
  struct stat file {};
  if (const int held = s.confirmed_socket.load();
      held >= 0 && fstat(held, &file) == 0 && file.st_nlink > 0)
    return false;
  // Opened before the identity is read: a hub replaced in between is seen by the identity.
  const int socket_file = open(kRoudiSocketPath, O_PATH | O_CLOEXEC);
  const std::uint64_t attached = s.attached_hub, now = hub_instance_now();
  if (socket_file >= 0 && (attached == 0 || now != attached))
    close(socket_file);
  else if (socket_file >= 0)
    s.confirmed_socket.store(socket_file);
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
