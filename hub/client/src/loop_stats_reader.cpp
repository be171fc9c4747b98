// Discovery of loop stats channels (see loop_stats_reader.hpp).
#include "afhub/hub/loop_stats_reader.hpp"

#include <thread>

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

std::vector<LoopStats> LoopStatsReader::all(std::chrono::milliseconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  for (;;) {
    std::vector<LoopStats> loops = latest();
    // Until iceoryx's registry reaches this process, no channel is found, not even the
    // hub's own health.
    const bool registry_arrived = !discovery_.live_instances(kHealthEvent).empty();
    if ((registry_arrived && loops.size() == readers_.size()) ||
        std::chrono::steady_clock::now() >= deadline)
      return loops;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

}  // namespace afhub
