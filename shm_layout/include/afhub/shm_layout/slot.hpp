// A latest-value slot: the control block of an entry in a block of slots
// (slot_block.hpp) that a writer updates in place for as long as it lives; readers
// hold the block and copy the entry's payload out. No lock is shared: the writer makes
// the sequence odd, writes the payload, makes it even again (a seqlock), and a reader
// keeps a copy only when the sequence was the same even number before and after it
// copied. A writer killed mid-update leaves the sequence odd: its readers keep their
// last copy and recognise the slot as torn, until a restarted writer claims a new one.
#pragma once

#include <atomic>
#include <cstdint>

#include "afhub/shm_layout/header.hpp"

namespace afhub {

struct SlotControl {
  // Odd while the writer updates the payload; +2 per update. Also the futex word a
  // waiting reader sleeps on (32 bits, as a futex is).
  std::atomic<std::uint32_t> sequence{0};
  // Set by a reader about to sleep on `sequence`; the writer that finds it set clears
  // it and wakes the sleepers. A flag rather than a count: a reader killed asleep
  // costs the writer one futex_wake, not one on every update from then on.
  std::atomic<std::uint32_t> sleeping{0};
  // The payload's publish stamp (monotonic_ns) of the last finished update, readable
  // without copying the payload: a reader holding several writers' slots of one
  // channel (commands) takes the newest.
  std::atomic<std::int64_t> stamp_ns{0};
  // The bytes of the payload the update wrote (at most the chunk's): a reader copies
  // these. A writer's payloads may be shorter than its slot (a state of fewer joints).
  std::atomic<std::uint32_t> payload_bytes{0};
};

// Lock-free in shared memory: the atomics must not fall back to a process-local lock.
static_assert(std::atomic<std::uint32_t>::is_always_lock_free);
static_assert(std::atomic<std::int64_t>::is_always_lock_free);

// The kinds written as slots: written every period, read as latest values (states,
// commands, a viewer's pose feed). The rest (catalog, directories, world commands,
// health, stats, scene, soft body meshes, bench samples) are queues of iceoryx
// samples, each published once.
constexpr bool is_slot_kind(PayloadKind kind) {
  switch (kind) {
    case PayloadKind::kBodyState:
    case PayloadKind::kBodyCommand:
    case PayloadKind::kWorldState:
    case PayloadKind::kDeviceState:
    case PayloadKind::kDeviceCommand:
    case PayloadKind::kScenePoses:
    case PayloadKind::kBenchSlot:
      return true;
    default:
      return false;
  }
}

}  // namespace afhub
