// StepTape: a physics' body states of one step (of the bodies whose state slot someone
// holds), the commands it took for them and its world state, for a reader that must see
// every step (`afhub record`), on {"afhub", <world instance>, "step_tape"}. A state is a
// latest-value slot: a reader that wakes a step late finds the newer state, and the one
// before is gone. The tape keeps the last kStepTapeRingParts parts instead, in a ring
// that the physics publishes once (when something first subscribes) and then writes in
// place, each part under a sequence of its own (a seqlock): a reader that falls behind
// (a busy core, a pause) catches up, and loses parts only when the writer laps it. No
// iceoryx publish per step, and a reader costs the writer nothing. A step's states fill
// as many parts as they need, the last one marked.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

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

// What a ring is, written once before it is published.
struct StepTapeRingId {
  std::uint64_t magic{0};      // kStepTapeRingMagic
  std::uint64_t layout_id{0};  // kLayoutId of the writer's build
  std::int64_t made_ns{0};     // monotonic: a reader that came before starts at part 0
  std::uint32_t writer_pid{0};
  std::uint32_t part_count{0};  // kStepTapeRingParts
};

struct alignas(64) StepTapeRingPart {
  // 0 before the ring's k-th part (counted from 0 since the ring was made) is written
  // here, 2k+1 while the writer fills it, 2k+2 once it is whole.
  std::atomic<std::uint64_t> sequence{0};
  alignas(64) StepTape tape;
};

struct StepTapeRing {
  StepTapeRingId id;
  // Parts whole since the ring was made: where a reader that was lapped starts again.
  alignas(64) std::atomic<std::uint64_t> written{0};
  std::array<StepTapeRingPart, kStepTapeRingParts> parts;
};
static_assert(std::atomic<std::uint64_t>::is_always_lock_free);

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
