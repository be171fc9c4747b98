// The reading end of a tape (see tape_reader.hpp).
#include "afhub/hub/tape_reader.hpp"

#include <cstdio>
#include <cstring>
#include <utility>

#include "afhub/hub/hub_health.hpp"
#include "afhub/shm_layout/payload_check.hpp"
#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"
#include "tape_ports.hpp"

namespace afhub {

namespace {

// A copied part checked as what it holds: a step tape's part as one payload (its
// entries are checked by its reader, as what each is), a device's state and the command
// it took.
PayloadError check_part(const StepTape& part, std::uint32_t bytes, const char** field) noexcept {
  return check_payload(&part, bytes, PayloadKind::kStepTape, field);
}
PayloadError check_part(const DeviceTape& part, std::uint32_t, const char** field) noexcept {
  const PayloadError state =
      check_payload(&part.state, sizeof part.state, PayloadKind::kDeviceState, field);
  if (state != PayloadError::kNone || !part.has_command) return state;
  return check_payload(&part.command, sizeof part.command, PayloadKind::kDeviceCommand, field);
}

}  // namespace

template <class Ring>
struct TapeReader<Ring>::Port {
  explicit Port(const std::string& instance)
      : subscriber(tape_service<Ring>(instance), newest_sample_only()) {}
  iox::popo::UntypedSubscriber subscriber;
};

template <class Ring>
TapeReader<Ring>::TapeReader(const std::string& instance) : made_ns_(monotonic_ns()) {
  require_subscriber_ports(
      1, std::string("reading ") + tape_names<Ring>().what + " of '" + instance + "'");
  port_ = std::make_unique<Port>(instance);
  took_subscriber_port();
}

template <class Ring>
TapeReader<Ring>::~TapeReader() {
  if (ring_) port_->subscriber.release(ring_);
  if (next_ring_) port_->subscriber.release(next_ring_);
  gave_back_subscriber_port();
}

template <class Ring>
void TapeReader<Ring>::refuse(const char* what, const char* why) noexcept {
  if (refused_++ == 0)
    std::fprintf(stderr, "afhub: refused %s's %s: %s (said once)\n", tape_names<Ring>().what, what,
                 why);
}

// Takes a ring published since the last look (a restarted writer's), checked by its
// copied id, to read once the one in hand has no more. True when a ring is in hand.
template <class Ring>
bool TapeReader<Ring>::take_rings() noexcept {
  for (;;) {
    auto taken = port_->subscriber.take();
    if (taken.has_error()) break;
    const void* chunk = taken.value();
    TapeRingId id;
    std::memcpy(&id, chunk, sizeof id);
    const char* why =
        iox::mepoo::ChunkHeader::fromUserPayload(chunk)->userPayloadSize() != sizeof(Ring)
            ? "its size is not a ring's"
        : id.magic != Ring::kRingMagic      ? "TapeRingId.magic"
        : id.layout_id != kLayoutId         ? "TapeRingId.layout_id (another build)"
        : id.part_count != Ring::kPartCount ? "TapeRingId.part_count"
                                            : nullptr;
    if (why) {
      refuse("ring", why);
      port_->subscriber.release(chunk);
      continue;
    }
    if (next_ring_) port_->subscriber.release(next_ring_);
    next_ring_ = static_cast<const Ring*>(chunk);
  }
  if (!ring_ && next_ring_) {
    ring_ = std::exchange(next_ring_, nullptr);
    cursor_ = ring_->id.made_ns > made_ns_ ? 0 : tape_ring::head(*ring_);
  }
  return ring_ != nullptr;
}

template <class Ring>
bool TapeReader<Ring>::next(Part& out) noexcept {
  // Laps and ring changes are few; the bound keeps a ring written absurdly from
  // holding the caller.
  for (int turns = 0; turns < 8 && take_rings();) {
    std::uint32_t bytes = 0;
    switch (tape_ring::read(*ring_, cursor_, out, bytes)) {
      case tape_ring::Read::kCopied: {
        ++cursor_;
        const char* field = "";
        const PayloadError error = check_part(out, bytes, &field);
        if (error == PayloadError::kNone) return true;
        refuse(field, describe(error));
        ++turns;
        break;
      }
      case tape_ring::Read::kOverwritten: {
        const std::uint64_t resumed = tape_ring::resume_after_lap(*ring_, cursor_);
        lost_ += resumed - cursor_;
        cursor_ = resumed;
        ++turns;
        break;
      }
      case tape_ring::Read::kNotYet:
        if (!next_ring_) return false;
        // The writer of the ring in hand is gone: its last part read, on to the new one.
        port_->subscriber.release(std::exchange(ring_, nullptr));
        ring_ = std::exchange(next_ring_, nullptr);
        cursor_ = 0;
        ++turns;
        break;
    }
  }
  return false;
}

template class TapeReader<StepTapeRing>;
template class TapeReader<DeviceTapeRing>;

}  // namespace afhub
