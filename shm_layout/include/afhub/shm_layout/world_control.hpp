// How a simulating process obeys world commands: pause, resume, a number of single
// steps while paused, and reset (which the caller carries out on its own state).
#pragma once

#include <algorithm>
#include <cstdint>

#include "afhub/shm_layout/limits.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub {

struct WorldControl {
  bool paused = false;
  std::uint64_t steps_to_run = 0;

  // Returns true when the command asks for a reset.
  bool apply(const WorldCommand& command) noexcept {
    switch (command.action) {
      case WorldAction::kPause:  // also ends single steps still to run
        paused = true;
        steps_to_run = 0;
        break;
      case WorldAction::kResume:
        paused = false;
        steps_to_run = 0;
        break;
      case WorldAction::kStep:
        // Only while paused: steps asked for while running would otherwise pile up
        // and all run at the next pause.
        if (paused)
          steps_to_run = std::min<std::uint64_t>(
              steps_to_run + std::min(command.step_count, kMaxWorldStepsPerCommand),
              kMaxWorldStepsPerCommand);
        break;
      case WorldAction::kReset:
        steps_to_run = 0;
        return true;
      case WorldAction::kNone:
        break;
    }
    return false;
  }

  // What the world state says: paused only while no single steps are left to run (a
  // world running `world step N` is not standing still).
  bool halted() const noexcept { return paused && steps_to_run == 0; }

  // Whether to advance this cycle; a single step asked for while paused is used up.
  bool take_step() noexcept {
    if (!paused) return true;
    if (steps_to_run == 0) return false;
    --steps_to_run;
    return true;
  }
};

}  // namespace afhub
