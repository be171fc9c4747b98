// Discovery of loop stats channels (see loop_stats_reader.hpp).
#include "afhub/hub/loop_stats_reader.hpp"

namespace afhub {

std::vector<LoopStats> LoopStatsReader::latest() {
  discovery_.follow(kStatsEvent, readers_, [](const std::string& instance) {
    return std::make_unique<LatestReader<LoopStats>>(
        ChannelId{std::string(kService), instance, std::string(kStatsEvent)});
  });
  std::vector<LoopStats> out;
  for (const auto& [instance, reader] : readers_)
    if (const LoopStats* stats = reader->latest()) out.push_back(*stats);
  return out;
}

}  // namespace afhub
