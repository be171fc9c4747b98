// WorldState and WorldCommand: the simulation clock and its controls.
#pragma once

#include <cstdint>

#include <array>

#include "afhub/shm_layout/geometry.hpp"
#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

// A light or camera of the world file: its name and pose (x forward for a camera
// looking along it, z up; a light shines along its x axis).
struct WorldObjectPose {
  std::array<char, kChannelNameBufferSize> name{};
  Pose pose;
};

struct WorldState {
  static constexpr PayloadKind kKind = PayloadKind::kWorldState;
  PayloadHeader header;          // sim_step and sim_time_s are the world's clock
  double wall_time_s{0.0};       // since the simulation started
  double achieved_rate_hz{0.0};  // steps per wall-clock second, over the last second
  // The physics' phase: its steps are due at step_due_ns + k step_period_ns
  // (CLOCK_MONOTONIC); step_due_ns is this step's (as BodyState.step_due_ns). Both 0
  // when it is not paced by the clock (--fast).
  std::int64_t step_due_ns{0};
  std::int64_t step_period_ns{0};
  std::uint32_t body_count{0};
  std::uint8_t paused{0};
  std::uint8_t lockstep{0};  // stepping waits for the lockstep clients
  // While paused: whether the pause is held (WorldCommand.hold_ms: it lapses once its
  // holder goes quiet), and the pid of the process whose pause command is in force (a
  // physics started paused: its own; over DDS: the bridge's on the physics' machine).
  std::uint8_t pause_held{0};
  std::uint8_t reserved{0};
  // Commands refused since the start (NaN or Inf, a value beyond the body's physical
  // bounds, a joint index beyond the body's joints), watchdog expiries (a body's
  // commands stopped for too long), and commands not applied because they were
  // older than their body's watchdog period when read (by their publish stamp).
  std::uint64_t rejected_commands{0};
  std::uint64_t watchdog_expiries{0};
  std::uint64_t stale_commands{0};
  // Lockstep: clients in the barrier now, steps taken without a late client's
  // answer, and clients dropped from the barrier after repeated misses.
  std::uint32_t lockstep_clients{0};
  std::uint32_t paused_by_pid{0};
  std::uint64_t late_answers{0};
  std::uint64_t dropped_clients{0};
  // Command timeliness, summed over the bodies under command: steps taken, and
  // steps whose command answered the state published just before (it arrived in
  // time for the step). A controller stamps header.sim_step with the state it answers.
  std::uint64_t commanded_steps{0};
  std::uint64_t answered_steps{0};
  // Bodies the physics put back after a step made them NaN or infinite, counted once
  // per body per step (`afhub run` recovers instead of ending the world; with
  // --stop-on-nan it stops), and the last of them: its channel and the step.
  std::uint64_t nan_recoveries{0};
  std::uint64_t last_nan_step{0};
  std::array<char, kChannelNameBufferSize> last_nan_body{};
  std::uint32_t light_count{0};
  std::uint32_t camera_count{0};
  std::array<WorldObjectPose, kMaxWorldObjects> lights{};
  std::array<WorldObjectPose, kMaxWorldObjects> cameras{};
};

// Whether the world is under a pause: halted (`paused`), or running the steps asked of
// it by hand (`afhub world step N`), which do not run it on (paused_by_pid stays).
constexpr bool under_pause(const WorldState& world) noexcept {
  return world.paused != 0 || world.paused_by_pid != 0;
}

enum class WorldAction : std::uint32_t {
  kNone = 0,
  kPause = 1,
  kResume = 2,
  kStep = 3,  // while paused: advance step_count steps (ignored while running)
  kReset = 4,
  kRelease = 5,  // ends its sender's held pause: the world runs on unless another holds it
};

// As `afhub world` names it: "pause", "resume", "step", "reset"; "none" otherwise.
constexpr const char* action_name(WorldAction action) noexcept {
  switch (action) {
    case WorldAction::kPause:
      return "pause";
    case WorldAction::kResume:
      return "resume";
    case WorldAction::kStep:
      return "step";
    case WorldAction::kReset:
      return "reset";
    case WorldAction::kRelease:
      return "release";
    default:
      return "none";
  }
}

// Each command is acted on once, in the order it arrived, identified by its header's
// (publisher_pid, sequence): every writer's sequence starts at 1.
struct WorldCommand {
  static constexpr PayloadKind kKind = PayloadKind::kWorldCommand;
  PayloadHeader header;
  WorldAction action{WorldAction::kNone};
  std::uint32_t step_count{1};
  // kPause: 0, paused until resumed; N, a held pause, which lasts while its publisher's
  // commands (any action, kNone included) keep coming less than N ms apart. A client
  // that pauses the world to step it (AMBF's step throttling) holds its pause: should it
  // die or stall, the world runs on, as AMBF's does once its throttling client is quiet.
  std::uint32_t hold_ms{0};
  // How long its sender waits to see it acted on, ms from its publish stamp (0: no
  // bound). Read later, it is dropped and said: a command its sender reported failed
  // never acts later (a physics stopped past an `afhub world reset --timeout 1` that
  // failed reset the world once resumed).
  std::uint32_t valid_ms{0};
};

}  // namespace afhub
