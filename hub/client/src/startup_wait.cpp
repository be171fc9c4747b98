// Waiting for the hub and a body at start (see startup_wait.hpp).
#include "afhub/hub/startup_wait.hpp"

#include <chrono>
#include <cmath>
#include <limits>

#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/header.hpp"

namespace afhub {
namespace {

double checked_seconds(double seconds) {
  if (!(seconds >= 0.0 && seconds <= 1e6))
    throw Error(
        "--wait takes a number of seconds from 0 to 1e6 (how long to wait for the hub "
        "and then what this process uses)");
  return seconds;
}

}  // namespace

StartupWait::StartupWait(double seconds)
    : seconds_(checked_seconds(seconds)),
      give_up_ns_(reattach_count() > 0 ? std::numeric_limits<std::int64_t>::max()
                                       : monotonic_ns() + std::llround(seconds * 1e9)) {}

void StartupWait::connect_to_hub(const std::string& role) const {
  afhub::connect_to_hub(role, HubPolicy::kRequire,
                        std::chrono::milliseconds(std::llround(seconds_ * 1e3)));
}

BodyEntry StartupWait::wait_for_body(const std::string& query, const std::string& who,
                                     const std::string& hint) const {
  return afhub::wait_for_body(query, who, give_up_ns_, hint);
}

}  // namespace afhub
