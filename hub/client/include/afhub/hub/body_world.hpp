// The world state of the physics that publishes a body: the world of a namespace the
// body's channel starts with ("a/b", "a" or "" for "a/b/c": `afhub run --namespace`),
// innermost first, whose publisher also published the body's state, at the same step
// within two (a state left by a dead physics whose pid was reused, or a physics of
// another pid namespace, is not it). A teleop reads its pause, a lockstep controller
// whether the physics waits for it.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "afhub/hub/channel.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub {

class BodyWorld {
 public:
  // Readers of the candidate worlds (one port per kind: states are slots), each read
  // once here (a reader's copies are made at its first state). Throws Error when the
  // hub has no port to give.
  explicit BodyWorld(std::string_view body_channel);

  // The newest world state of the physics that published `body` (this reader's copy),
  // or nullptr when no candidate matches. No heap allocation once each world's first
  // state was read.
  const WorldState* of(const BodyState& body) noexcept;
  // The namespace of that world (`afhub run --namespace`; "" for none), or nullptr.
  const std::string* name_space_of(const BodyState& body) noexcept;

 private:
  struct Candidate {
    std::string name_space;
    std::unique_ptr<LatestReader<WorldState>> reader;
  };
  struct Found {
    const WorldState* state = nullptr;
    const std::string* name_space = nullptr;
  };
  Found find(const BodyState& body) noexcept;
  std::vector<Candidate> worlds_;  // innermost first
};

}  // namespace afhub
