// Zero-copy channel ends over iceoryx's untyped publisher and subscriber.
#include "afhub/hub/channel.hpp"

#include <time.h>
#include <unistd.h>

#include <cstdio>

#include "afhub/hub/hub_health.hpp"
#include "afhub/shm_layout/error.hpp"
#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/untyped_publisher.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"
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
  Port(const ChannelId& channel, History history)
      : publisher(describe_channel(channel), [history] {
          iox::popo::PublisherOptions options;
          options.historyCapacity = history == History::kKeepLast ? 1 : 0;
          return options;
        }()) {}
  iox::popo::UntypedPublisher publisher;
};

RawWriter::RawWriter(const ChannelId& channel, PayloadKind kind, History history)
    : channel_(channel), kind_(kind), pid_(static_cast<std::uint32_t>(getpid())) {
  require_fits(channel);
  require_publisher_ports(1, "writing '" + channel.to_string() + "'");
  port_ = std::make_unique<Port>(channel, history);
  took_publisher_port();
}

RawWriter::~RawWriter() {
  if (port_) gave_back_publisher_port();
}

void* RawWriter::loan(std::uint32_t bytes) noexcept {
  auto result = port_->publisher.loan(bytes, alignof(PayloadHeader));
  return result.has_error() ? nullptr : result.value();
}

std::int64_t RawWriter::publish(void* payload) noexcept {
  auto* header = static_cast<PayloadHeader*>(payload);
  header->layout_id = kLayoutId;
  header->kind = kind_;
  header->publisher_pid = pid_;
  header->sequence = ++sequence_;
  const std::int64_t stamp = header->publish_stamp_ns = monotonic_ns();
  port_->publisher.publish(payload);
  return stamp;
}

bool RawWriter::has_readers() const noexcept {
  return port_->publisher.hasSubscribers();
}

RawLatestReader::Port::Port(const ChannelId& channel, History history)
    : subscriber(describe_channel(channel), [history] {
        iox::popo::SubscriberOptions options;
        options.queueCapacity = 1;  // latest value: a newer sample replaces a queued one
        options.historyRequest = history == History::kKeepLast ? 1 : 0;
        options.queueFullPolicy = iox::popo::QueueFullPolicy::DISCARD_OLDEST_DATA;
        return options;
      }()) {}

RawLatestReader::RawLatestReader(const ChannelId& channel, PayloadKind kind)
    : channel_(channel), kind_(kind) {
  require_fits(channel);
  require_subscriber_ports(1, "reading '" + channel.to_string() + "'");
  port_ = std::make_unique<Port>(channel, history_of(kind));
  took_subscriber_port();
}

RawLatestReader::~RawLatestReader() {
  gave_back_subscriber_port();
  if (held_) port_->subscriber.release(held_);
  if (retired_) port_->subscriber.release(retired_);
}

const void* RawLatestReader::latest() noexcept {
  updated_ = false;
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
      report_refusal(payload, error, field);
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

void RawLatestReader::report_refusal(const void* payload, PayloadError error,
                                     const char* field) noexcept {
  // Said once per reader: a foreign writer publishes at its own rate.
  if (refused_++ > 0) return;
  PayloadHeader header{};
  const std::uint32_t bytes = iox::mepoo::ChunkHeader::fromUserPayload(payload)->userPayloadSize();
  if (bytes >= sizeof header) header = *static_cast<const PayloadHeader*>(payload);
  std::fprintf(stderr,
               "afhub: refused a payload on %s/%s/%s from pid %u (layout id %016llx, this "
               "build %016llx): %s: %s (said once per reader)\n",
               channel_.service.c_str(), channel_.instance.c_str(), channel_.event.c_str(),
               header.publisher_pid, static_cast<unsigned long long>(header.layout_id),
               static_cast<unsigned long long>(kLayoutId), field, describe(error));
}

}  // namespace afhub
