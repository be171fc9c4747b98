// Waiting for updates (see sample_waiter.hpp): on the futexes of the slots the
// readers hold, or on iceoryx's WaitSet (queue readers, and slot readers that hold no
// slot yet, which look again every kArrivalCheckNs).
#include "afhub/hub/sample_waiter.hpp"

#include <linux/futex.h>

#include <algorithm>
#include <vector>

#include "iceoryx_posh/popo/wait_set.hpp"
#include "latest_slot.hpp"
#include "reader_port.hpp"
#include "slot_blocks.hpp"

namespace afhub {
namespace {

// A slot's futex says nothing of a new writer's entry (a restarted physics, a second
// controller): a wait on slots returns this often, and the readers look for one. Not
// sooner: a timer a millisecond away, armed on every wait, made each wake-up of a
// halted vCPU about 5 us slower on the project's VM (a lockstep round trip 1.36x the
// bare futex floor with a 1 ms look, 1.09x with 10 ms, in the same hour: physics_benchmark's
// BM_LockstepRoundTrip/one_body_apart; docs/performance.md#lockstep).
constexpr std::int64_t kArrivalCheckNs = 10'000'000;
// Slots past the 128 that futex_waitv watches are looked at this often.
constexpr std::int64_t kUnwatchedCheckNs = 1'000'000;

}  // namespace

struct SampleWaiter::WaitSet {
  iox::popo::WaitSet<> set;
  std::vector<RawLatestReader*> readers;
  std::vector<slot::Watch> watches;  // reserved at attach: wait() does not allocate
};

const std::size_t SampleWaiter::kCapacity = iox::MAX_NUMBER_OF_ATTACHMENTS_PER_WAITSET;

SampleWaiter::SampleWaiter() : wait_set_(std::make_unique<WaitSet>()) {}

SampleWaiter::~SampleWaiter() = default;

bool SampleWaiter::attach(RawLatestReader& reader) {
  if (wait_set_->readers.size() >= kCapacity) return false;
  if (!reader.slots_) {
    // A state, not an event: the wait returns while a sample waits in the reader's
    // queue, so a sample that came before the wait is never missed.
    auto result =
        wait_set_->set.attachState(reader.port_->subscriber, iox::popo::SubscriberState::HAS_DATA);
    if (result.has_error()) return false;
  }
  wait_set_->readers.push_back(&reader);
  wait_set_->watches.reserve(wait_set_->readers.size() * RawLatestReader::kMaxHeldSlots);
  return true;
}

void SampleWaiter::wait(std::int64_t timeout_ns) noexcept {
  if (timeout_ns <= 0) return;
  std::vector<slot::Watch>& watches = wait_set_->watches;
  watches.clear();
  bool looking = false;  // a slot reader has not found its writer yet
  for (RawLatestReader* reader : wait_set_->readers) {
    if (!reader->slots_) {
      if (reader->port_->subscriber.hasData()) return;  // a sample waits
      continue;
    }
    looking |= reader->held_slot_count_ == 0;
    for (std::size_t i = 0; i < reader->held_slot_count_; ++i)
      watches.push_back({&reader->held_slots_[i].entry->control, reader->observed_[i]});
  }
  if (watches.empty()) {
    wait_set_->set.timedWait(iox::units::Duration::fromNanoseconds(
        looking ? std::min(timeout_ns, kArrivalCheckNs) : timeout_ns));
    return;
  }
  slot::wait(watches, std::min(timeout_ns, watches.size() > FUTEX_WAITV_MAX ? kUnwatchedCheckNs
                                                                            : kArrivalCheckNs));
}

}  // namespace afhub
