// Zero-copy channel ends over iceoryx's untyped publisher and subscriber.
#include "afhub/hub/channel.hpp"

#include <time.h>
#include <unistd.h>

#include <cstdio>

#include "afhub/hub/hub_health.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/slot.hpp"
#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/untyped_publisher.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"
#include "latest_slot.hpp"
#include "reader_port.hpp"

namespace afhub {
namespace {

iox::capro::ServiceDescription describe_channel(const ChannelId& channel) {
  using iox::capro::IdString_t;
  using iox::cxx::TruncateToCapacity;
  // Names were validated on the way in; nothing here is ever truncated.
  return {IdString_t(TruncateToCapacity, channel.service.c_str()),
          IdString_t(TruncateToCapacity, channel.instance.c_str()),
          IdString_t(TruncateToCapacity, channel.event.c_str())};
}

void require_fits(const ChannelId& channel) {
  for (const std::string* part : {&channel.service, &channel.instance, &channel.event})
    if (part->empty() || part->size() > iox::capro::IdString_t::capacity())
      throw Error("channel '" + channel.to_string() + "': '" + *part +
                  "' must have 1 to 100 characters");
}

}  // namespace

struct RawWriter::Port {
  explicit Port(const ChannelId& channel)
      : publisher(describe_channel(channel), [] {
          iox::popo::PublisherOptions options;
          // The last sample (a queue's) or the slot, for readers that come later.
          options.historyCapacity = 1;
          return options;
        }()) {}
  iox::popo::UntypedPublisher publisher;
};

RawWriter::RawWriter(const ChannelId& channel, PayloadKind kind)
    : channel_(channel), kind_(kind), pid_(static_cast<std::uint32_t>(getpid())) {
  require_fits(channel);
  require_publisher_ports(1, "writing '" + channel.to_string() + "'");
  port_ = std::make_unique<Port>(channel);
  took_publisher_port();
}

RawWriter::~RawWriter() {
  if (!port_) return;
  if (slot_payload_ && !slot_published_) port_->publisher.release(slot_payload_);
  gave_back_publisher_port();
}

void* RawWriter::loan(std::uint32_t bytes) noexcept {
  if (!is_slot_kind(kind_)) {
    auto result = port_->publisher.loan(bytes, alignof(PayloadHeader));
    return result.has_error() ? nullptr : result.value();
  }
  if (slot_payload_ && bytes <= slot_bytes_) {
    slot::begin_update(*slot_, bytes);
    return slot_payload_;
  }
  // The first loan, or a larger payload than the slot holds: a new slot, which
  // readers take in place of this writer's old one when it is published.
  auto result = port_->publisher.loan(bytes, alignof(PayloadHeader), sizeof(SlotControl),
                                      alignof(SlotControl));
  if (result.has_error()) return nullptr;
  if (slot_payload_ && !slot_published_) port_->publisher.release(slot_payload_);
  slot_payload_ = result.value();
  slot_ = new (iox::mepoo::ChunkHeader::fromUserPayload(slot_payload_)->userHeader()) SlotControl;
  slot::init(*slot_);
  slot::begin_update(*slot_, bytes);
  slot_bytes_ = bytes;
  slot_published_ = false;
  return slot_payload_;
}

std::int64_t RawWriter::publish(void* payload) noexcept {
  auto* header = static_cast<PayloadHeader*>(payload);
  header->layout_id = kLayoutId;
  header->kind = kind_;
  header->publisher_pid = pid_;
  header->sequence = ++sequence_;
  const std::int64_t stamp = header->publish_stamp_ns = monotonic_ns();
  if (!is_slot_kind(kind_)) {
    port_->publisher.publish(payload);
    return stamp;
  }
  slot::end_update(*slot_, stamp);
  if (!slot_published_) {  // once per slot: from now on readers hold it
    port_->publisher.publish(payload);
    slot_published_ = true;
  }
  return stamp;
}

bool RawWriter::has_readers() const noexcept {
  return port_->publisher.hasSubscribers();
}

RawLatestReader::Port::Port(const ChannelId& channel, bool slots)
    : subscriber(describe_channel(channel), [slots] {
        iox::popo::SubscriberOptions options;
        // A queue: a newer sample replaces a queued one. Slots: room for a few
        // writers' slots arriving between two looks.
        options.queueCapacity = slots ? RawLatestReader::kMaxHeldSlots : 1;
        options.historyRequest = 1;
        options.queueFullPolicy = iox::popo::QueueFullPolicy::DISCARD_OLDEST_DATA;
        return options;
      }()) {}

RawLatestReader::RawLatestReader(const ChannelId& channel, PayloadKind kind)
    : channel_(channel), kind_(kind), slots_(is_slot_kind(kind)) {
  require_fits(channel);
  require_subscriber_ports(1, "reading '" + channel.to_string() + "'");
  port_ = std::make_unique<Port>(channel, slots_);
  took_subscriber_port();
}

RawLatestReader::~RawLatestReader() {
  gave_back_subscriber_port();
  if (slots_) {
    for (std::size_t i = 0; i < held_slot_count_; ++i)
      port_->subscriber.release(held_slots_[i].payload);
    return;
  }
  if (held_) port_->subscriber.release(held_);
  if (retired_) port_->subscriber.release(retired_);
}

const void* RawLatestReader::latest() noexcept {
  updated_ = false;
  return slots_ ? latest_slot() : latest_queued();
}

const void* RawLatestReader::latest_queued() noexcept {
  // The sample replaced by the last call is released now, while polling, rather
  // than between a new sample's arrival and its reader seeing it.
  if (retired_) port_->subscriber.release(retired_);
  retired_ = nullptr;
  for (;;) {
    auto taken = port_->subscriber.take();
    if (taken.has_error()) break;  // no more samples (or too many held: keep the current)
    const void* payload = taken.value();
    const std::uint32_t bytes =
        iox::mepoo::ChunkHeader::fromUserPayload(payload)->userPayloadSize();
    const char* field = "";
    PayloadError error = check_payload(payload, bytes, kind_, &field);
    if (error != PayloadError::kNone) {
      report_refusal(payload, bytes, field, describe(error));
      port_->subscriber.release(payload);
      continue;
    }
    if (retired_) port_->subscriber.release(retired_);
    retired_ = held_;
    held_ = payload;
    held_bytes_ = bytes;
    updated_ = true;
  }
  return held_;
}

void RawLatestReader::subscribe() noexcept {
  port_->subscriber.subscribe();
}

void RawLatestReader::unsubscribe() noexcept {
  port_->subscriber.unsubscribe();
}

bool RawLatestReader::subscribed() const noexcept {
  return port_->subscriber.getSubscriptionState() == iox::SubscribeState::SUBSCRIBED;
}

void RawLatestReader::take_slot(const void* payload) noexcept {
  const auto* chunk = iox::mepoo::ChunkHeader::fromUserPayload(payload);
  auto* control = static_cast<SlotControl*>(const_cast<void*>(chunk->userHeader()));
  if (chunk->userHeaderSize() < sizeof(SlotControl) || control->magic != kSlotMagic) {
    // Most likely a writer of another build: its layout id says so, if it has one.
    const char* field = "slot";
    const PayloadError error = check_payload(payload, chunk->userPayloadSize(), kind_, &field);
    report_refusal(
        payload, chunk->userPayloadSize(), field,
        error != PayloadError::kNone ? describe(error) : "a sample, not a latest-value slot");
    port_->subscriber.release(payload);
    return;
  }
  const HeldSlot slot{payload, control, chunk->userPayloadSize(),
                      static_cast<std::uint64_t>(chunk->originId()), ~0U};
  // A writer's new slot replaces its old one; a new writer takes a free place, or
  // the place of the writer updated longest ago (most likely gone).
  std::size_t place = held_slot_count_;
  for (std::size_t i = 0; i < held_slot_count_; ++i)
    if (held_slots_[i].origin == slot.origin) place = i;
  if (place == held_slot_count_ && held_slot_count_ == kMaxHeldSlots) {
    place = 0;
    for (std::size_t i = 1; i < held_slot_count_; ++i)
      if (held_slots_[i].control->stamp_ns.load(std::memory_order_relaxed) <
          held_slots_[place].control->stamp_ns.load(std::memory_order_relaxed))
        place = i;
  }
  if (place == held_slot_count_)
    ++held_slot_count_;
  else
    port_->subscriber.release(held_slots_[place].payload);
  held_slots_[place] = slot;
}

bool RawLatestReader::grow_copies(std::uint32_t bytes) noexcept {
  if (bytes <= copy_capacity_) return true;
  // Once per channel, when its first (or a larger) slot arrives: not in steady state.
  std::unique_ptr<unsigned char[]> copy(new (std::nothrow) unsigned char[bytes]);
  std::unique_ptr<unsigned char[]> spare(new (std::nothrow) unsigned char[bytes]);
  if (!copy || !spare) return false;
  if (held_) std::memcpy(copy.get(), held_, held_bytes_);
  copy_ = std::move(copy);
  spare_ = std::move(spare);
  copy_capacity_ = bytes;
  if (held_) held_ = copy_.get();
  return true;
}

const void* RawLatestReader::latest_slot() noexcept {
  for (;;) {
    auto taken = port_->subscriber.take();
    if (taken.has_error()) break;
    take_slot(taken.value());
  }
  if (held_slot_count_ == 0) return held_;
  // The writer that updated last; the others count as looked at (a wait then
  // sleeps until one of them updates again).
  std::size_t newest = 0;
  std::int64_t newest_stamp = held_slots_[0].control->stamp_ns.load(std::memory_order_acquire);
  for (std::size_t i = 1; i < held_slot_count_; ++i) {
    const std::int64_t stamp = held_slots_[i].control->stamp_ns.load(std::memory_order_acquire);
    if (stamp > newest_stamp) {
      newest = i;
      newest_stamp = stamp;
    }
  }
  for (std::size_t i = 0; i < held_slot_count_; ++i)
    if (i != newest)
      held_slots_[i].observed = held_slots_[i].control->sequence.load(std::memory_order_acquire);
  HeldSlot& slot = held_slots_[newest];
  if (!grow_copies(slot.bytes)) return held_;
  std::uint32_t bytes = 0;
  if (slot::read(*slot.control, slot.payload, slot.bytes, spare_.get(), slot.observed, bytes) !=
      slot::Read::kCopied)
    return held_;
  // Checked after the copy: the writer cannot change what was checked.
  const char* field = "";
  const PayloadError error = check_payload(spare_.get(), bytes, kind_, &field);
  if (error != PayloadError::kNone) {
    report_refusal(spare_.get(), bytes, field, describe(error));
    return held_;
  }
  copy_.swap(spare_);
  held_ = copy_.get();
  held_bytes_ = bytes;
  updated_ = true;
  return held_;
}

void RawLatestReader::report_refusal(const void* payload, std::uint32_t bytes, const char* field,
                                     const char* problem) noexcept {
  // Said once per reader: a foreign writer publishes at its own rate.
  if (refused_++ > 0) return;
  PayloadHeader header{};
  if (bytes >= sizeof header) std::memcpy(&header, payload, sizeof header);
  std::fprintf(stderr,
               "afhub: refused a payload on %s/%s/%s from pid %u (layout id %016llx, this "
               "build %016llx): %s: %s (said once per reader)\n",
               channel_.service.c_str(), channel_.instance.c_str(), channel_.event.c_str(),
               header.publisher_pid, static_cast<unsigned long long>(header.layout_id),
               static_cast<unsigned long long>(kLayoutId), field, problem);
}

}  // namespace afhub
