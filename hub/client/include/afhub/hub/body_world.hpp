// The world state of the physics that publishes a body: the world of a namespace the
// body's channel starts with ("", "a", "a/b" for "a/b/c": `afhub run --namespace`)
// whose publisher also published the body's state. A teleop reads its paused flag, a
// lockstep controller whether the physics waits for it.
#pragma once

#include <memory>
#include <string_view>
#include <vector>

#include "afhub/hub/channel.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub {

class BodyWorld {
 public:
  // Readers of the candidate worlds (one port per kind: states are slots). Throws
  // Error when the hub has no port to give.
  explicit BodyWorld(std::string_view body_channel);

  // The newest world state of the process that published `body` (this reader's copy),
  // or nullptr when none of the candidates has one. Real-time safe.
  const WorldState* of(const BodyState& body) noexcept;

 private:
  std::vector<std::unique_ptr<LatestReader<WorldState>>> worlds_;
};

}  // namespace afhub
