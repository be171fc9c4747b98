// Discovery of loop stats channels (see loop_stats_reader.hpp).
#include "afhub/hub/loop_stats_reader.hpp"

#include <set>

#include "iceoryx_posh/runtime/service_discovery.hpp"

namespace afhub {

LoopStatsReader::LoopStatsReader()
    : discovery_(std::make_unique<iox::runtime::ServiceDiscovery>()) {}

LoopStatsReader::~LoopStatsReader() = default;

std::vector<LoopStats> LoopStatsReader::latest() {
  std::set<std::string> live;
  discovery_->findService(
      iox::capro::IdString_t(iox::cxx::TruncateToCapacity, std::string(kService).c_str()),
      iox::cxx::nullopt,
      iox::capro::IdString_t(iox::cxx::TruncateToCapacity, std::string(kStatsEvent).c_str()),
      [&](const iox::capro::ServiceDescription& service) {
        live.insert(service.getInstanceIDString().c_str());
      },
      iox::popo::MessagingPattern::PUB_SUB);
  std::erase_if(readers_, [&](const auto& entry) { return !live.count(entry.first); });
  std::vector<LoopStats> out;
  for (const std::string& instance : live) {
    auto& reader = readers_[instance];
    if (!reader)
      reader = std::make_unique<LatestReader<LoopStats>>(
          ChannelId{std::string(kService), instance, std::string(kStatsEvent)});
    if (const LoopStats* stats = reader->latest()) out.push_back(*stats);
  }
  return out;
}

}  // namespace afhub
