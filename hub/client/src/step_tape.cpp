// The writing end of a world's step tape (see step_tape.hpp).
#include "afhub/hub/step_tape.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <utility>

#include "afhub/hub/hub_health.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/packed_body_state.hpp"
#include "iceoryx_posh/popo/untyped_publisher.hpp"
#include "tape_ports.hpp"

namespace afhub {

namespace {

// The largest entry fits a part, so add() never cuts a step short for one entry's size
// (a state packed is at most its whole size).
static_assert(step_tape_entry_bytes(kMaxChannelNameLength,
                                    std::max({body_state_bytes(kMaxJointsPerBody),
                                              body_command_bytes(kMaxJointsPerBody),
                                              sizeof(WorldState)})) <= sizeof(StepTape::data));

}  // namespace

struct StepTapeWriter::Port {
  explicit Port(const std::string& world)
      : publisher(tape_service<StepTapeRing>(world), ring_publisher_options()) {}
  iox::popo::UntypedPublisher publisher;
};

StepTapeWriter::StepTapeWriter(const std::string& world_instance)
    : pid_(static_cast<std::uint32_t>(getpid())) {
  require_publisher_ports(1, "writing the step tape of '" + world_instance + "'");
  port_ = std::make_unique<Port>(world_instance);
  took_publisher_port();
}

StepTapeWriter::~StepTapeWriter() {
  gave_back_publisher_port();
}

bool StepTapeWriter::begin(std::uint64_t step, double time_s) noexcept {
  finish();  // a step left unfinished is closed as it is, never held
  if (!port_->publisher.hasSubscribers()) return false;
  // Published once, at a reader's first step: then written in place.
  if (!ring_ && !(ring_ = publish_ring<StepTapeRing>(port_->publisher, pid_))) return false;
  step_ = step;
  time_s_ = time_s;
  part_ = 0;
  entries_ = 0;
  lost_ = false;
  next_part();
  return true;
}

void StepTapeWriter::next_part() noexcept {
  if (prepared_ > 0) {
    tape_ = &ring_->parts[next_ % kStepTapeRingParts].tape;
    --prepared_;
  } else {
    tape_ = &tape_ring::open(*ring_, next_);
  }
  ++next_;
  tape_->header.sim_step = step_;
  tape_->header.sim_time_s = time_s_;
  tape_->part = part_++;
  tape_->last_part = 0;
  tape_->first_entry = entries_;
  tape_->entry_count = 0;
  tape_->data_bytes = 0;
}

void StepTapeWriter::add(PayloadKind kind, std::string_view channel, const void* payload,
                         std::uint32_t bytes) noexcept {
  if (lost_ || !tape_) return;  // the step's tape is cut short: its reader counts what it misses
  // A state goes on packed: with 8 joints, 508 of its 1184 bytes (the tape's copy is most
  // of the physics' cost of taping a thousand bodies, and the ring holds more steps).
  PackedPieces pieces{std::span(static_cast<const std::uint8_t*>(payload), bytes)};
  if (kind == PayloadKind::kBodyState) {
    pieces = packed_pieces(*static_cast<const BodyState*>(payload));
    bytes = 0;
    for (const auto& piece : pieces) bytes += static_cast<std::uint32_t>(piece.size());
  }
  const std::size_t need = step_tape_entry_bytes(channel.size(), bytes);
  if (need > tape_->data.size()) {  // cannot happen: see the static_assert above
    lost_ = true;
    return;
  }
  if (tape_->data_bytes + need > tape_->data.size()) {
    close_part();
    next_part();
  }
  std::uint8_t* at = tape_->data.data() + tape_->data_bytes;
  const StepTapeEntry entry{static_cast<std::uint32_t>(channel.size()), bytes, kind, 0};
  std::memcpy(at, &entry, sizeof entry);
  std::memcpy(at + sizeof entry, channel.data(), channel.size());
  std::uint8_t* to = at + step_tape_payload_offset(channel.size());
  for (const auto& piece : pieces) {
    if (piece.empty()) continue;
    std::memcpy(to, piece.data(), piece.size());
    to += piece.size();
  }
  tape_->data_bytes += static_cast<std::uint32_t>(need);
  ++tape_->entry_count;
  ++entries_;
}

void StepTapeWriter::finish() noexcept {
  if (!tape_) return;
  tape_->last_part = lost_ ? 0 : 1;
  last_step_parts_ = part_;
  last_part_bytes_ = tape_->data_bytes;
  close_part();
  tape_ = nullptr;
}

void StepTapeWriter::close_part() noexcept {
  PayloadHeader& header = tape_->header;
  header.layout_id = kLayoutId;
  header.kind = PayloadKind::kStepTape;
  header.publisher_pid = pid_;
  header.sequence = ++sequence_;
  header.publish_stamp_ns = monotonic_ns();
  tape_ring::close(*ring_, next_ - 1);
}

void StepTapeWriter::prepare() noexcept {
  if (!ring_ || prepared_ > 0 || tape_ || !port_->publisher.hasSubscribers()) return;
  prepared_ = std::min(last_step_parts_, kMaxPreparedParts);
  for (std::uint32_t p = 0; p < prepared_; ++p) {
    StepTape& part = tape_ring::open(*ring_, next_ + p);
    // A part before the step's last was filled up to an entry's size of its end.
    const std::size_t bytes =
        p + 1 == last_step_parts_ ? offsetof(StepTape, data) + last_part_bytes_ : sizeof part;
    std::memset(static_cast<void*>(&part), 0, bytes);
  }
}

}  // namespace afhub
