// TapeRing: a ring of parts in shared memory that one writer fills in order and readers
// copy out, for what must reach a reader whole even when it wakes late: a physics' steps
// (step_tape.hpp), a device's cycles (device_tape.hpp). The writer publishes the ring
// once, when a reader first subscribes, and then writes each part in place under a
// sequence of its own (a seqlock): a reader that falls behind catches up, and loses parts
// only when the writer laps it. No iceoryx publish per part, and a reader costs the
// writer nothing.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

namespace afhub {

// What a ring is, written once before it is published.
struct TapeRingId {
  std::uint64_t magic{0};      // the ring's kind (kStepTapeRingMagic, kDeviceTapeRingMagic)
  std::uint64_t layout_id{0};  // kLayoutId of the writer's build
  std::int64_t made_ns{0};     // monotonic: a reader that came before starts at part 0
  std::uint32_t writer_pid{0};
  std::uint32_t part_count{0};
};

template <class Part>
struct alignas(64) TapeRingPart {
  // 0 before the ring's k-th part (counted from 0 since the ring was made) is written
  // here, 2k+1 while the writer fills it, 2k+2 once it is whole.
  std::atomic<std::uint64_t> sequence{0};
  alignas(64) Part tape;
};

template <class Part, std::uint32_t kParts, std::uint64_t kMagic>
struct TapeRing {
  using PartType = Part;
  static constexpr std::uint32_t kPartCount = kParts;
  static constexpr std::uint64_t kRingMagic = kMagic;
  TapeRingId id;
  // Parts whole since the ring was made: where a reader that was lapped starts again.
  alignas(64) std::atomic<std::uint64_t> written{0};
  std::array<TapeRingPart<Part>, kParts> parts;
};
static_assert(std::atomic<std::uint64_t>::is_always_lock_free);

}  // namespace afhub
