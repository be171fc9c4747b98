// Outliving the hub (see hub_loss.hpp): the opt-in, and the re-attachment after a
// re-exec (hub_reattach.hpp).
#include "afhub/hub/hub_loss.hpp"

#include <cstdio>
#include <cstdlib>
#include <optional>

#include "afhub/hub/hub_presence.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/header.hpp"
#include "hub_loss_handling.hpp"
#include "hub_loss_state.hpp"
#include "hub_loss_watcher.hpp"
#include "hub_reattach.hpp"
#include "iceoryx_error_handler.hpp"
#include "keepalive_sink.hpp"
#include "self_reexec.hpp"

namespace afhub {

void survive_hub_loss(const std::string& who) {
  hub_loss::State& s = hub_loss::state();
  if (s.armed) return;
  s.who = who;
  if (const char* value = std::getenv(hub_loss::kReattachVariable)) {
    unsigned count = 0;
    unsigned long long lost_hub = 0;
    long long lost_at = 0, carried = 0;
    if (std::sscanf(value, "%u:%llu:%lld:%lld", &count, &lost_hub, &lost_at, &carried) == 4) {
      s.reattach_count = count;
      s.lost_hub = lost_hub;
      s.lost_at_ns = lost_at;
      s.carried = carried;
    }
    unsetenv(hub_loss::kReattachVariable);
    hub_loss::unblock_stop_signals();  // blocked across the re-exec; the handlers are in
  }
  hub_loss::prepare_self_reexec();  // after unsetenv: the next image gets a fresh count
  hub_loss::install_iceoryx_error_handler();
  s.reexecs = true;
  s.armed = true;
}

void notice_hub_loss(const std::string& who) {
  hub_loss::State& s = hub_loss::state();
  if (s.armed) return;
  s.who = who;
  hub_loss::install_iceoryx_error_handler();
  s.armed = true;
}

void on_hub_lost(std::function<void()> make_safe) {
  hub_loss::State& s = hub_loss::state();
  std::lock_guard<std::mutex> lock(s.hooks_mutex);
  s.hooks.push_back(std::move(make_safe));
}

bool hub_lost() noexcept {
  return hub_loss::state().lost.load(std::memory_order_relaxed);
}

unsigned reattach_count() noexcept {
  return hub_loss::state().reattach_count;
}

void carry_into_reattach(std::int64_t value) noexcept {
  hub_loss::state().carried.store(value, std::memory_order_relaxed);
}

std::int64_t carried_from_before_reattach() noexcept {
  return hub_loss::state().reattach_count > 0 ? hub_loss::state().carried.load() : 0;
}

namespace hub_loss {

bool reattaching() noexcept {
  return state().armed && state().reattach_count > 0;
}

void wait_for_new_hub() {
  const State& s = state();
  std::fprintf(stderr, "%s: waiting for a hub to re-attach to\n", s.who.c_str());
  for (;;) {
    if (stop_requested()) {
      std::fprintf(stderr, "%s: stopped while waiting for a hub\n", s.who.c_str());
      std::exit(0);
    }
    const std::uint64_t before = hub_instance_now();
    if (before != 0 && before != s.lost_hub && probe_roudi() == RoudiPresence::kRunning &&
        hub_instance_now() == before)
      return;
    sleep_ns(kReattachPollNs);
  }
}

void watch_attached_hub(std::int64_t hub_seen_ns) {
  State& s = state();
  if (!s.armed) return;
  // Registered after the runtime, so that it runs before the runtime's destructor.
  std::atexit([] { state().exiting = true; });
  // The hub this process saw before registering (RegistrationGuard), not one read now:
  // each hub writes its identity before its socket answers, so a hub that replaced it
  // since was taken for this process's own (it stayed on the dead one's memory, or
  // waited for a hub other than the live one). Kept, the watcher sees it replaced. The
  // error is now the other way: a hub replaced just before the registration was sent
  // is taken for lost, and the process re-attaches to it once more than needed.
  if (s.attached_hub == 0)
    if (const std::optional<HubIdentity> hub = running_hub()) {
      s.attached_hub = hub->instance;
      s.attached_hub_pid = hub->pid;
    }
  if (!s.reexecs) {
    s.roudi_socket = find_roudi_socket();
    s.runtime_name = runtime_name();
  }
  if (s.reattach_count > 0)
    std::fprintf(stderr,
                 "%s: re-attached to the hub (pid %d), %.0f ms after it answered and %.2f s after "
                 "the last one was lost\n",
                 s.who.c_str(), static_cast<int>(s.attached_hub_pid),
                 static_cast<double>(monotonic_ns() - hub_seen_ns) * 1e-6,
                 static_cast<double>(monotonic_ns() - s.lost_at_ns) * 1e-9);
  start_hub_loss_watcher();
}

}  // namespace hub_loss
}  // namespace afhub
