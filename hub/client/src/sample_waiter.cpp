// Waiting for samples on iceoryx's WaitSet (see sample_waiter.hpp).
#include "afhub/hub/sample_waiter.hpp"

#include "iceoryx_posh/popo/wait_set.hpp"
#include "reader_port.hpp"

namespace afhub {

struct SampleWaiter::WaitSet {
  iox::popo::WaitSet<> set;
  std::size_t attached = 0;
};

const std::size_t SampleWaiter::kCapacity = iox::MAX_NUMBER_OF_ATTACHMENTS_PER_WAITSET;

SampleWaiter::SampleWaiter() : wait_set_(std::make_unique<WaitSet>()) {}

SampleWaiter::~SampleWaiter() = default;

bool SampleWaiter::attach(RawLatestReader& reader) {
  // A state, not an event: the wait returns while a sample waits in the reader's
  // queue, so a sample that came before the wait is never missed.
  if (wait_set_->attached >= kCapacity) return false;
  auto result =
      wait_set_->set.attachState(reader.port_->subscriber, iox::popo::SubscriberState::HAS_DATA);
  if (result.has_error()) return false;
  ++wait_set_->attached;
  return true;
}

void SampleWaiter::wait(std::int64_t timeout_ns) noexcept {
  if (timeout_ns <= 0) return;
  wait_set_->set.timedWait(iox::units::Duration::fromNanoseconds(timeout_ns));
}

}  // namespace afhub
