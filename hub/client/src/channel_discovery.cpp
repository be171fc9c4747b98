// Service discovery (see channel_discovery.hpp).
#include "afhub/hub/channel_discovery.hpp"

#include "afhub/hub/hub_health.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "iceoryx_posh/runtime/service_discovery.hpp"

namespace afhub {

// iceoryx's service discovery reads its registry with a subscriber of its own.
ChannelDiscovery::ChannelDiscovery() {
  require_subscriber_ports(1, "finding live channels");
  discovery_ = std::make_unique<iox::runtime::ServiceDiscovery>();
  took_subscriber_port();
}

ChannelDiscovery::~ChannelDiscovery() {
  gave_back_subscriber_port();
}

std::set<std::string> ChannelDiscovery::live_instances(std::string_view event) {
  const std::string service_name(kService), event_name(event);
  std::set<std::string> live;
  discovery_->findService(
      iox::capro::IdString_t(iox::cxx::TruncateToCapacity, service_name.c_str()), iox::cxx::nullopt,
      iox::capro::IdString_t(iox::cxx::TruncateToCapacity, event_name.c_str()),
      [&](const iox::capro::ServiceDescription& service) {
        live.insert(service.getInstanceIDString().c_str());
      },
      iox::popo::MessagingPattern::PUB_SUB);
  return live;
}

}  // namespace afhub
