// The hub watched while this process registers (see registration_guard.hpp).
#include "registration_guard.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <optional>

#include "afhub/hub/hub_presence.hpp"
#include "hub_loss_handling.hpp"
#include "hub_loss_state.hpp"

namespace afhub {
namespace {

// The hub's socket answers and its identity is known; noted the first time, as the hub
// the loss check compares with and the one a re-exec waits to see replaced. A hub still
// starting (started with this process, or by it) is not one that went away.
bool hub_seen() noexcept {
  hub_loss::State& s = hub_loss::state();
  if (s.attached_hub == 0) {
    try {
      if (const std::optional<HubIdentity> hub = running_hub()) {
        s.attached_hub_pid = hub->pid;
        s.attached_hub = hub->instance;
      }
    } catch (...) {
    }
  }
  return s.attached_hub != 0 && probe_roudi() == RoudiPresence::kRunning;
}

}  // namespace

RegistrationGuard::RegistrationGuard(std::string who) : who_(std::move(who)) {
  seen_ = hub_seen();  // before iceoryx sends anything: a hub killed at once is seen gone
  thread_ = std::thread([this] { watch(); });
}

RegistrationGuard::~RegistrationGuard() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
  }
  registered_.notify_one();
  thread_.join();
}

void RegistrationGuard::watch() noexcept {
  std::unique_lock<std::mutex> lock(mutex_);
  bool seen = seen_;
  for (int strikes = 0; strikes < 2;) {  // one failed look is not a loss, as after registering
    if (registered_.wait_for(lock, std::chrono::milliseconds(20), [this] { return done_; })) return;
    if (!seen)
      seen = hub_seen();
    else
      strikes = hub_loss::hub_gone() ? strikes + 1 : 0;
  }
  end_registration();
}

void RegistrationGuard::end_registration() noexcept {
  constexpr const char* kWhy = "while registering this process";
  if (hub_loss::state().armed) {
    switch (hub_loss::handle_loss(kWhy)) {  // re-executes a process that outlives its hub
      case hub_loss::LossHandling::kOtherThread:
        hub_loss::wait_for_reexec();
      case hub_loss::LossHandling::kStopping:
        _exit(0);
      case hub_loss::LossHandling::kCarriesOn:  // said so; it cannot carry on unregistered
        break;
    }
  } else {
    std::fprintf(stderr, "%s: the hub (pid %d) went away %s: run it again once a hub runs\n",
                 who_.c_str(), static_cast<int>(hub_loss::state().attached_hub_pid), kWhy);
  }
  std::fflush(nullptr);
  _exit(1);
}

}  // namespace afhub
