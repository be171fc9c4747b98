// WorldState and WorldCommand: the simulation clock and its controls.
#pragma once

#include <cstdint>

#include "afhub/shm_layout/header.hpp"

namespace afhub {

struct WorldState {
  static constexpr PayloadKind kKind = PayloadKind::kWorldState;
  PayloadHeader header;          // sim_step and sim_time_s are the world's clock
  double wall_time_s{0.0};       // since the simulation started
  double achieved_rate_hz{0.0};  // steps per wall-clock second, over the last second
  std::uint32_t body_count{0};
  std::uint8_t paused{0};
  std::uint8_t reserved[3]{};
};

enum class WorldAction : std::uint32_t {
  kNone = 0,
  kPause = 1,
  kResume = 2,
  kStep = 3,  // while paused: advance step_count steps
  kReset = 4,
};

// Each command is acted on once, identified by its header sequence number.
struct WorldCommand {
  static constexpr PayloadKind kKind = PayloadKind::kWorldCommand;
  PayloadHeader header;
  WorldAction action{WorldAction::kNone};
  std::uint32_t step_count{1};
};

}  // namespace afhub
