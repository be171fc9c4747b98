// The ends of a world's step tape (see step_tape.hpp).
#include "afhub/hub/step_tape.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <utility>

#include "afhub/hub/hub_health.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/payload_check.hpp"
#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"

namespace afhub {

namespace {
ChannelId tape_channel(const std::string& world_instance) {
  return {std::string(kService), world_instance, std::string(kStepTapeEvent)};
}
}  // namespace

StepTapeWriter::StepTapeWriter(const std::string& world_instance)
    : writer_(tape_channel(world_instance), PayloadKind::kStepTape) {}

StepTapeWriter::~StepTapeWriter() {
  if (prepared_) writer_.release(prepared_);
}

bool StepTapeWriter::begin(std::uint64_t step, double time_s) noexcept {
  finish();  // a step left unfinished goes out as it is, never held
  if (!writer_.has_readers()) return false;
  step_ = step;
  time_s_ = time_s;
  part_ = 0;
  entries_ = 0;
  lost_ = false;
  return next_part();
}

// A new part to fill, loaned whole so that it comes from the tape's own pool.
bool StepTapeWriter::next_part() noexcept {
  tape_ = part_ == 0 && prepared_ ? std::exchange(prepared_, nullptr)
                                  : static_cast<StepTape*>(writer_.loan(sizeof(StepTape)));
  if (!tape_) {
    lost_ = true;  // shared memory exhausted: the rest of the step's tape is missed
    return false;
  }
  tape_->header.sim_step = step_;
  tape_->header.sim_time_s = time_s_;
  tape_->part = part_++;
  tape_->last_part = 0;
  tape_->first_entry = entries_;
  tape_->entry_count = 0;
  tape_->data_bytes = 0;
  return true;
}

void StepTapeWriter::add(PayloadKind kind, std::string_view channel, const void* payload,
                         std::uint32_t bytes) noexcept {
  if (lost_) return;  // the step's tape is cut short: its reader counts what it misses
  const std::size_t need = step_tape_entry_bytes(channel.size(), bytes);
  if (!tape_ || need > tape_->data.size()) {  // cannot happen: a payload fits a part
    lost_ = true;
    return;
  }
  if (tape_->data_bytes + need > tape_->data.size()) {
    publish_part();
    if (!next_part()) return;
  }
  std::uint8_t* at = tape_->data.data() + tape_->data_bytes;
  const StepTapeEntry entry{static_cast<std::uint32_t>(channel.size()), bytes, kind, 0};
  std::memcpy(at, &entry, sizeof entry);
  std::memcpy(at + sizeof entry, channel.data(), channel.size());
  std::memcpy(at + step_tape_payload_offset(channel.size()), payload, bytes);
  tape_->data_bytes += static_cast<std::uint32_t>(need);
  ++tape_->entry_count;
  ++entries_;
}

void StepTapeWriter::finish() noexcept {
  if (!tape_) return;
  tape_->last_part = lost_ ? 0 : 1;
  publish_part();
  tape_ = nullptr;
}

void StepTapeWriter::publish_part() noexcept {
  if (tape_->part == 0) first_part_bytes_ = tape_->data_bytes;
  writer_.publish(tape_);
}

void StepTapeWriter::prepare() noexcept {
  if (!writer_.has_readers()) {
    if (prepared_) writer_.release(std::exchange(prepared_, nullptr));
    return;
  }
  if (prepared_) return;
  prepared_ = static_cast<StepTape*>(writer_.loan(sizeof(StepTape)));
  if (prepared_)
    std::memset(static_cast<void*>(prepared_), 0, offsetof(StepTape, data) + first_part_bytes_);
}

struct StepTapeReader::Port {
  explicit Port(const std::string& world)
      : subscriber(
            {iox::capro::IdString_t(iox::cxx::TruncateToCapacity, kService.data(), kService.size()),
             iox::capro::IdString_t(iox::cxx::TruncateToCapacity, world.data(), world.size()),
             iox::capro::IdString_t(iox::cxx::TruncateToCapacity, kStepTapeEvent.data(),
                                    kStepTapeEvent.size())},
            [] {
              iox::popo::SubscriberOptions options;
              options.queueCapacity = kStepTapeQueue;
              // The writer never waits: past the queue the oldest part goes.
              options.queueFullPolicy = iox::popo::QueueFullPolicy::DISCARD_OLDEST_DATA;
              return options;
            }()) {}
  iox::popo::UntypedSubscriber subscriber;
};

static_assert(kStepTapeQueue <= iox::MAX_SUBSCRIBER_QUEUE_CAPACITY);

StepTapeReader::StepTapeReader(const std::string& world_instance) {
  require_subscriber_ports(1, "reading the step tape of '" + world_instance + "'");
  port_ = std::make_unique<Port>(world_instance);
  took_subscriber_port();
}

StepTapeReader::~StepTapeReader() {
  gave_back_subscriber_port();
}

bool StepTapeReader::next(StepTape& out) noexcept {
  for (;;) {
    auto taken = port_->subscriber.take();
    if (taken.has_error()) return false;
    const void* payload = taken.value();
    const std::uint32_t chunk_bytes =
        iox::mepoo::ChunkHeader::fromUserPayload(payload)->userPayloadSize();
    // Copied before it is checked: its used part, as its copied header says.
    std::uint32_t bytes = 0;
    if (chunk_bytes >= offsetof(StepTape, data) && chunk_bytes <= sizeof out) {
      std::memcpy(static_cast<void*>(&out), payload, offsetof(StepTape, data));
      bytes = static_cast<std::uint32_t>(offsetof(StepTape, data)) +
              std::min<std::uint32_t>(out.data_bytes, chunk_bytes - offsetof(StepTape, data));
      std::memcpy(out.data.data(),
                  static_cast<const std::uint8_t*>(payload) + offsetof(StepTape, data),
                  bytes - offsetof(StepTape, data));
    }
    port_->subscriber.release(payload);
    const char* field = "";
    const PayloadError error = bytes == 0
                                   ? PayloadError::kTooSmall
                                   : check_payload(&out, bytes, PayloadKind::kStepTape, &field);
    if (error == PayloadError::kNone) return true;
    if (refused_++ == 0)
      std::fprintf(stderr, "afhub: refused a step tape sample: %s: %s (said once)\n", field,
                   describe(error));
  }
}

}  // namespace afhub
