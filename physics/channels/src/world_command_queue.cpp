// The world command queue (see world_command_queue.hpp).
#include "world_command_queue.hpp"

#include <cstdio>
#include <cstring>

#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/payload_check.hpp"
#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"

namespace afhub::physics {

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
              // World command writers keep their last command (History::kKeepLast):
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
    : port_(std::make_unique<Port>(world_instance)) {}

WorldCommandQueue::~WorldCommandQueue() = default;

bool WorldCommandQueue::next(WorldCommand& out) noexcept {
  for (;;) {
    auto taken = port_->subscriber.take();
    if (taken.has_error()) return false;
    const void* payload = taken.value();
    const std::uint32_t bytes =
        iox::mepoo::ChunkHeader::fromUserPayload(payload)->userPayloadSize();
    const char* field = "";
    const PayloadError error = check_payload(payload, bytes, PayloadKind::kWorldCommand, &field);
    if (error == PayloadError::kNone) std::memcpy(&out, payload, sizeof out);
    port_->subscriber.release(payload);
    if (error == PayloadError::kNone) return true;
    if (!told_refused_)
      std::fprintf(stderr, "afhub run: refused a world command: %s: %s\n", field, describe(error));
    told_refused_ = true;
  }
}

}  // namespace afhub::physics
