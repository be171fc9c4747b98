// A loop's late commands for one body as its physics counts them: the body's state
// carries the steps taken under command and those answered in time, so that the loop's
// stats, `afhub top` and `afhub status` agree. Used by `afhub ctl` and Python's
// afhub.Loop, which count the growth between the states they answer.
#pragma once

#include <cstdint>

#include "afhub/shm_layout/body_state.hpp"

namespace afhub {

class PhysicsLateCommands {
 public:
  // The commands the physics counted late since the last state given; 0 for the first
  // state of a physics (another pid: a restarted physics counts from 0 again).
  std::uint32_t newly_late(const BodyState& state) noexcept {
    const std::uint32_t late = state.commanded_steps - state.answered_steps;  // modulo 2^32
    const std::uint32_t grown = state.header.publisher_pid == physics_pid_ ? late - late_ : 0;
    physics_pid_ = state.header.publisher_pid;
    late_ = late;
    return grown;
  }

 private:
  std::uint32_t late_ = 0, physics_pid_ = 0;
};

}  // namespace afhub
