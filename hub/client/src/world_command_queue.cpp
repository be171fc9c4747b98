// The world command queue (see world_command_queue.hpp).
#include "afhub/hub/world_command_queue.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "afhub/hub/hub_health.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/payload_check.hpp"
#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"

namespace afhub {

struct WorldCommandQueue::Port {
  explicit Port(const std::string& world)
      : subscriber(
            {iox::capro::IdString_t(iox::cxx::TruncateToCapacity, kService.data(), kService.size()),
             iox::capro::IdString_t(iox::cxx::TruncateToCapacity, world.data(), world.size()),
             iox::capro::IdString_t(iox::cxx::TruncateToCapacity, kCommandEvent.data(),
                                    kCommandEvent.size())},
            [] {
              iox::popo::SubscriberOptions options;
              options.queueCapacity = kCapacity;
              // World command writers keep their last command (their history):
              // ask for it, so that one sent while this subscription was being set
              // up is not lost; the caller drops those older than the physics.
              options.historyRequest = 1;
              options.queueFullPolicy = iox::popo::QueueFullPolicy::DISCARD_OLDEST_DATA;
              return options;
            }()) {}
  iox::popo::UntypedSubscriber subscriber;
};

static_assert(WorldCommandQueue::kCapacity <= iox::MAX_SUBSCRIBER_QUEUE_CAPACITY);

WorldCommandQueue::WorldCommandQueue(const std::string& world_instance)
    : created_ns_(monotonic_ns()) {
  require_subscriber_ports(1, "reading the world commands of '" + world_instance + "'");
  port_ = std::make_unique<Port>(world_instance);
  took_subscriber_port();
}

WorldCommandQueue::~WorldCommandQueue() {
  gave_back_subscriber_port();
}

bool WorldCommandQueue::seen(const PayloadHeader& header) noexcept {
  for (Writer& writer : writers_) {
    if (writer.pid != header.publisher_pid || writer.stamp_ns == 0) continue;
    // The same writer: a sequence it used already is a repeat, unless its stamp is
    // newer (another process that got the same pid, its sequence from 1 again).
    if (header.sequence <= writer.sequence && header.publish_stamp_ns <= writer.stamp_ns)
      return true;
    writer.sequence = header.sequence;
    writer.stamp_ns = header.publish_stamp_ns;
    return false;
  }
  writers_[next_writer_] = {header.publisher_pid, header.sequence, header.publish_stamp_ns};
  next_writer_ = (next_writer_ + 1) % writers_.size();
  return false;
}

bool WorldCommandQueue::expired(const WorldCommand& command) noexcept {
  if (command.valid_ms == 0) return false;
  const std::int64_t age_ns = monotonic_ns() - command.header.publish_stamp_ns;
  if (age_ns <= static_cast<std::int64_t>(command.valid_ms) * 1'000'000) return false;
  // Said for the first few: a stopped physics may find its whole queue expired.
  if (++expired_said_ > kExpiredSaid) return true;
  std::fprintf(stderr,
               "afhub: ignored a world command (%s) from pid %u: read %.3f s after it was sent, "
               "past the %.3f s its sender waited for it (it said the command failed)\n",
               action_name(command.action), command.header.publisher_pid,
               static_cast<double>(age_ns) * 1e-9, command.valid_ms * 1e-3);
  if (expired_said_ == kExpiredSaid)
    std::fprintf(stderr, "afhub: (further world commands ignored so are not said)\n");
  return true;
}

bool WorldCommandQueue::next(WorldCommand& out) noexcept {
  for (;;) {
    auto taken = port_->subscriber.take();
    if (taken.has_error()) return false;
    const void* payload = taken.value();
    // Copied out, then checked: the writer could change it between a check and a copy.
    const std::uint32_t bytes = std::min<std::uint32_t>(
        iox::mepoo::ChunkHeader::fromUserPayload(payload)->userPayloadSize(), sizeof out);
    std::memcpy(&out, payload, bytes);
    port_->subscriber.release(payload);
    const char* field = "";
    const PayloadError error = check_payload(&out, bytes, PayloadKind::kWorldCommand, &field);
    if (error == PayloadError::kNone) {
      if (out.header.publish_stamp_ns < created_ns_ || seen(out.header)) continue;
      if (expired(out)) continue;
      return true;
    }
    if (!told_refused_)
      std::fprintf(stderr, "afhub: refused a world command: %s: %s\n", field, describe(error));
    told_refused_ = true;
  }
}

}  // namespace afhub
