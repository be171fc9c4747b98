// How a simulating process obeys world commands: pause, resume, a number of single
// steps while paused, and reset (which the caller carries out on its own state); a held
// pause lapses when its holder goes quiet.
#pragma once

#include <algorithm>
#include <cstdint>

#include "afhub/shm_layout/limits.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub {

// What a simulating process says when a held pause lapses (printf: the process's name,
// the holder's pid, its hold in ms). No allocation: said from the loop.
inline constexpr const char* kPauseLapsedFormat =
    "%s: the world's pause held by process %u lapsed, nothing from it for %u ms (it ended or "
    "stalls): the world runs on, as AMBF's does once its throttling client goes quiet\n";

struct WorldControl {
  bool paused = false;
  std::uint32_t paused_by_pid = 0;  // whose pause is in force
  std::uint64_t steps_to_run = 0;
  // A held pause (WorldCommand.hold_ms): its holder (0: none) and when it lapses unless
  // a command of the holder's comes first.
  std::uint32_t holder_pid = 0;
  std::int64_t hold_ns = 0;
  std::int64_t held_until_ns = 0;

  // Returns true when the command asks for a reset. `now_ns` times a held pause.
  bool apply(const WorldCommand& command, std::int64_t now_ns) noexcept {
    if (holder_pid != 0 && command.header.publisher_pid == holder_pid)
      held_until_ns = now_ns + hold_ns;
    switch (command.action) {
      case WorldAction::kPause:  // also ends single steps still to run
        // A plain pause (a user's) takes over a held one and holds until resumed; a held
        // pause asked for while plainly paused leaves the plain one in force. The last
        // holder holds.
        if (command.hold_ms == 0 || !paused || holder_pid != 0) {
          paused_by_pid = command.header.publisher_pid;
          holder_pid = command.hold_ms == 0 ? 0 : paused_by_pid;
          hold_ns = static_cast<std::int64_t>(command.hold_ms) * 1'000'000;
          held_until_ns = now_ns + hold_ns;
        }
        paused = true;
        steps_to_run = 0;
        break;
      case WorldAction::kResume:
        paused = false;
        paused_by_pid = 0;
        steps_to_run = 0;
        holder_pid = 0;
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

  // A held pause whose holder has been quiet for its hold: the world runs on. Returns
  // the holder's pid when it lapses now, for the caller to say; 0 otherwise.
  std::uint32_t lapse(std::int64_t now_ns) noexcept {
    if (holder_pid == 0 || now_ns <= held_until_ns) return 0;
    const std::uint32_t holder = holder_pid;
    holder_pid = 0;
    paused = false;
    paused_by_pid = 0;
    steps_to_run = 0;
    return holder;
  }

  // What the world state says: paused only while no single steps are left to run (a
  // world running `world step N` is not standing still).
  bool halted() const noexcept { return paused && steps_to_run == 0; }

  // The world state's pause fields: paused, whose pause and whether it is held.
  void describe_pause(WorldState& world) const noexcept {
    world.paused = halted();
    world.paused_by_pid = paused ? paused_by_pid : 0;
    world.pause_held = paused && holder_pid != 0;
  }

  // Whether to advance this cycle; a single step asked for while paused is used up.
  bool take_step() noexcept {
    if (!paused) return true;
    if (steps_to_run == 0) return false;
    --steps_to_run;
    return true;
  }
};

}  // namespace afhub
