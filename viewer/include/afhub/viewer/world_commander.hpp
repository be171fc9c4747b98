// The page's pause, resume, step and reset buttons (`afhub view --allow-commands`):
// a request "action=pause|resume|step|reset" sends one WorldCommand on the world's
// command channel, as `afhub world` does, without waiting: the page sees the
// result in the pose frames (the paused flag, the simulation time). Called from
// the server's threads.
#pragma once

#include <mutex>
#include <string>

#include "afhub/hub/channel.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub::viewer {

class WorldCommander {
 public:
  // Needs connect_to_hub(); `world` is the world's channel instance (world_instance()).
  explicit WorldCommander(const std::string& world);

  // Returns "" when the command was sent, else what is wrong with the request.
  std::string run(const std::string& query);

 private:
  std::mutex mutex_;
  Writer<WorldCommand> writer_;
  LatestReader<WorldState> state_;
};

}  // namespace afhub::viewer
