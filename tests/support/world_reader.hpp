// The physics' world state, read as it comes (needs connect_to_hub()).
#pragma once

#include <string>

#include "afhub/hub/channel.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub::test {

inline LatestReader<WorldState> world_reader() {
  return LatestReader<WorldState>(
      {std::string(kService), std::string(kWorldInstance), std::string(kStateEvent)});
}

}  // namespace afhub::test
