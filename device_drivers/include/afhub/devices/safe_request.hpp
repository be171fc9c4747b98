// Making a device safe from another thread than its loop's (the hub-loss hook runs on
// the hub watcher's), without two threads on the device at once: for a Falcon, two
// threads on one USB transport. The requester asks; the loop, between two exchanges,
// makes the device safe, answers and leaves the device alone from then on. A loop that
// does not answer in time (stuck in an exchange) leaves it to the requester.
#pragma once

#include <atomic>
#include <cstdint>

#include "afhub/devices/device.hpp"

namespace afhub::devices {

// Who made the device safe on a request.
enum class MadeSafeBy { kLoop, kRequester, kRequesterOnLoopThread, kNoDevice };

class SafeRequest {
 public:
  // The device the loop drives (nullptr: none; a request then does nothing). Detaching
  // waits for a request under way to finish with the device, which may then be freed.
  void attach(Device* device) noexcept;

  // On the loop's thread, before each exchange: true once a request came and the device
  // was made safe (here, or by the requester); the loop must not exchange then.
  bool serve() noexcept;

  // From any thread: asks the loop, waits up to timeout_ns for it to make the device
  // safe, and makes it safe itself when no answer came. On the loop's own thread (an
  // iceoryx call of the loop met the loss) the device is made safe at once.
  MadeSafeBy request(std::int64_t timeout_ns) noexcept;

 private:
  enum State : int { kIdle, kRequested, kLoopMaking, kLoopDone, kTakenOver };
  std::atomic<Device*> device_{nullptr};
  std::atomic<int> state_{kIdle};
  std::atomic<int> requests_in_flight_{0};
};

}  // namespace afhub::devices
