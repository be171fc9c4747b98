// Every live loop's stats channel ({"afhub", *, "stats"}), found through iceoryx's
// service discovery: what `afhub status` and `afhub top` show.
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "afhub/hub/channel.hpp"
#include "afhub/hub/channel_discovery.hpp"
#include "afhub/shm_layout/loop_stats.hpp"

namespace afhub {

class LoopStatsReader {
 public:
  // The newest stats of each live loop, ordered by process name. A loop that just
  // appeared may have published nothing yet: it is left out until it does.
  std::vector<LoopStats> latest();

  // The same, for a reader just opened: waits until every live loop has delivered (a
  // subscriber gets a loop's last stats on connecting, which iceoryx does for each reader
  // in its own discovery round; a loop publishes a second into its run, then each second)
  // or `limit` has passed. With no loop running it returns as soon as it can tell.
  std::vector<LoopStats> all(std::chrono::milliseconds limit);

 private:
  ChannelDiscovery discovery_;
  std::map<std::string, std::unique_ptr<LatestReader<LoopStats>>> readers_;
};

}  // namespace afhub
