// StepTape: a physics' body states of one step (of the bodies whose state slot someone
// holds), the commands it took for them and its world state, for a reader that must see
// every step (`afhub record`), on {"afhub", <world instance>, "step_tape"}. A state is a
// latest-value slot: a reader that wakes a step late finds the newer state, and the one
// before is gone. The tape keeps the last kStepTapeRingParts parts instead, in a ring
// (tape_ring.hpp). A step's states fill as many parts as they need, the last one marked.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "afhub/shm_layout/tape_ring.hpp"

namespace afhub {

// One part: the largest entry (a state of kMaxJointsPerBody joints, 25.7 KB with its
// name) fits, with room to spare: sixty 8-joint states, packed (544 bytes an entry). A
// step's states start a part of their own, so smaller parts waste less of the ring on
// small worlds.
inline constexpr std::size_t kStepTapeBytes = 32 * 1024;
// The ring's parts: 320 ms at 1 kHz of a world whose step fits one part (the example
// scene: 21 entries; a recorder must survive a pause of 150 ms and more), 18 steps of a
// thousand 8-joint bodies (17 parts a step; 8 steps when states were taped whole). Two
// rings take 21 MB of the hub's pools (hub/daemon/src/hub_mempools.cpp).
inline constexpr std::uint32_t kStepTapeRingParts = 320;
inline constexpr std::uint64_t kStepTapeRingMagic = 0x61666875622d7472ULL;  // "afhub-tr"

// An entry of a tape's data: this header, the body's channel name (name_bytes, no
// NUL; the world's instance for its state), then at the next multiple of 8 the payload
// (payload_bytes): a state packed (packed_body_state.hpp), a command as the physics
// took it, the world state; the next entry starts at the multiple of 8 after it.
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

using StepTapeRing = TapeRing<StepTape, kStepTapeRingParts, kStepTapeRingMagic>;

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
