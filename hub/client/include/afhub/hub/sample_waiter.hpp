// Blocks a thread until one of some readers has something new: an update of a slot
// it holds (a futex wait on the slots' sequences, which the writer wakes), or a
// sample in its queue (iceoryx's WaitSet, a futex-backed semaphore the writer's
// publish posts). A lockstep wait sleeps on it instead of spinning on sched_yield,
// which under SCHED_FIFO never gives the core to a client of lower or equal priority.
// Construct and attach before the loop (needs connect_to_hub()); wait() does not
// allocate.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "afhub/hub/channel.hpp"

namespace afhub {

class SampleWaiter {
 public:
  // How many readers one waiter watches (iceoryx's attachments per WaitSet).
  static const std::size_t kCapacity;

  SampleWaiter();
  ~SampleWaiter();
  SampleWaiter(const SampleWaiter&) = delete;
  SampleWaiter& operator=(const SampleWaiter&) = delete;

  // Watches `reader` (which must outlive this waiter). False when the waiter is full.
  bool attach(RawLatestReader& reader);
  // Returns as soon as an attached reader has a sample it has not taken with
  // latest(), or after `timeout_ns`.
  void wait(std::int64_t timeout_ns) noexcept;

 private:
  struct WaitSet;
  std::unique_ptr<WaitSet> wait_set_;
};

}  // namespace afhub
