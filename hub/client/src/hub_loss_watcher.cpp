// The hub-loss watcher thread (see hub_loss_watcher.hpp).
#include "hub_loss_watcher.hpp"

#include <thread>

#include "afhub/hub/hub_presence.hpp"
#include "hub_loss_handling.hpp"
#include "hub_loss_state.hpp"

namespace afhub::hub_loss {
namespace {

constexpr std::int64_t kWatchPeriodNs = 20'000'000;

void watch_hub() noexcept {
  State& s = state();
  int strikes = 0;  // two looks in a row, 20 ms apart: one failed open() is not a loss
  while (!s.lost) {
    sleep_ns(kWatchPeriodNs);
    if (s.exiting) return;
    strikes = hub_gone() ? strikes + 1 : 0;
    if (strikes < 2) continue;
    handle_loss(probe_roudi() == RoudiPresence::kRunning ? "another hub replaced it"
                                                         : "its socket no longer answers");
    return;
  }
}

}  // namespace

void start_hub_loss_watcher() {
  std::thread(watch_hub).detach();
}

}  // namespace afhub::hub_loss
