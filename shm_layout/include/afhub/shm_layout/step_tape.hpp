// StepTape: a physics' body states of one step (of the bodies whose state slot someone
// holds), the commands it took for them and its world state, for a reader that must see
// every step
// (`afhub record`), on {"afhub", <world instance>, "step_tape"}. A state is a
// latest-value slot: a reader that wakes a step late finds the newer state, and the one
// before is gone. The tape is a queue of iceoryx samples instead, published after the
// states and only while something subscribes: a subscriber's queue holds
// kStepTapeQueue samples, so a reader that falls behind (a busy core, a pause) catches
// up, and loses steps only when it falls further behind than its queue. A step's states
// fill as many samples as they need, its parts, the last one marked.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

// One sample, loaned whole so that it comes from a pool of its own
// (hub/daemon/src/hub_mempools.cpp): about fifty 8-joint states.
inline constexpr std::size_t kStepTapeBytes = 60 * 1024;
// A subscriber's queue: a quarter of a second at 1 kHz of a world whose states fit one
// sample (iceoryx 2.0.3's largest queue).
inline constexpr std::uint32_t kStepTapeQueue = 256;

// An entry of a tape's data: this header, the body's channel name (name_bytes, no
// NUL; the world's instance for its state), then at the next multiple of 8 the payload
// (payload_bytes): a state as published, or a command as the physics took it; the next
// entry starts at the multiple of 8 after it.
struct StepTapeEntry {
  std::uint32_t name_bytes{0};
  std::uint32_t payload_bytes{0};
  PayloadKind kind{PayloadKind::kBodyState};  // or kBodyCommand, kWorldState
  std::uint32_t reserved{0};
};

struct StepTape {
  static constexpr PayloadKind kKind = PayloadKind::kStepTape;
  PayloadHeader header;          // sim_step: the step of its states
  std::uint32_t part{0};         // of the step's samples, from 0
  std::uint32_t last_part{0};    // 1 on the step's last sample
  std::uint32_t first_entry{0};  // the step's entries in the parts before this one
  std::uint32_t entry_count{0};
  std::uint32_t data_bytes{0};  // entries fill data[0, data_bytes)
  std::uint32_t reserved{0};
  std::array<std::uint8_t, kStepTapeBytes - sizeof(PayloadHeader) - 24> data{};
};
static_assert(sizeof(StepTape) == kStepTapeBytes);

constexpr std::size_t round_up_to_8(std::size_t bytes) {
  return (bytes + 7) / 8 * 8;
}
// Where an entry's payload starts, from the entry's start; and the entry's whole size.
constexpr std::size_t step_tape_payload_offset(std::size_t name_bytes) {
  return round_up_to_8(sizeof(StepTapeEntry) + name_bytes);
}
constexpr std::size_t step_tape_entry_bytes(std::size_t name_bytes, std::size_t payload_bytes) {
  return step_tape_payload_offset(name_bytes) + round_up_to_8(payload_bytes);
}

}  // namespace afhub
