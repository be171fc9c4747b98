// Making a device safe across threads (see safe_request.hpp).
#include "afhub/devices/safe_request.hpp"

#include <time.h>

#include "afhub/rt/clock.hpp"

namespace afhub::devices {
namespace {

// The request this thread serves: set by serve(), so that a request made on the
// loop's own thread does not wait for itself.
thread_local const SafeRequest* t_served = nullptr;

void pause_100us() noexcept {
  timespec pause{0, 100'000};
  nanosleep(&pause, nullptr);
}

}  // namespace

void SafeRequest::attach(Device* device) noexcept {
  device_ = device;
  // Detached, the device may be freed next: a request that took it before finishes first.
  if (!device)
    while (requests_in_flight_.load() > 0) pause_100us();
}

bool SafeRequest::serve() noexcept {
  t_served = this;
  int state = state_.load();
  if (state == kIdle) return false;
  if (state == kRequested && state_.compare_exchange_strong(state, kLoopMaking)) {
    if (Device* device = device_.load()) device->make_safe();
    state_ = kLoopDone;
  }
  return true;
}

MadeSafeBy SafeRequest::request(std::int64_t timeout_ns) noexcept {
  struct InFlight {
    std::atomic<int>& count;
    explicit InFlight(std::atomic<int>& c) : count(c) { ++count; }
    ~InFlight() { --count; }
  } in_flight(requests_in_flight_);
  Device* device = device_.load();
  if (!device) return MadeSafeBy::kNoDevice;
  if (t_served == this) {
    state_ = kTakenOver;
    device->make_safe();
    return MadeSafeBy::kRequesterOnLoopThread;
  }
  int idle = kIdle;
  state_.compare_exchange_strong(idle, kRequested);
  const std::int64_t give_up = monotonic_ns() + timeout_ns;
  while (monotonic_ns() < give_up) {
    if (state_.load() == kLoopDone) return MadeSafeBy::kLoop;
    pause_100us();
  }
  int requested = kRequested;
  if (state_.compare_exchange_strong(requested, kTakenOver)) {
    device->make_safe();  // the loop is stuck in an exchange: it will not touch the device again
    return MadeSafeBy::kRequester;
  }
  // The loop took the request just now: its make_safe is under way.
  while (state_.load() == kLoopMaking && monotonic_ns() < give_up + timeout_ns) pause_100us();
  return MadeSafeBy::kLoop;
}

}  // namespace afhub::devices
