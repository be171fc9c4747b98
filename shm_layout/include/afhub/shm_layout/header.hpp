// The header that starts every payload: who wrote it, with which layout, and when.
#pragma once

#include <time.h>

#include <cstdint>

namespace afhub {

// Which payload a chunk holds. A reader checks it so that a channel carrying
// another type is refused instead of misread.
enum class PayloadKind : std::uint32_t {
  kBodyState = 1,
  kBodyCommand = 2,
  kWorldState = 3,
  kWorldCommand = 4,
  kBodyDirectory = 5,  // one process's bodies, read by the hub
  kCatalog = 6,        // every live body, published by the hub
  kHealth = 7,
  kLoopStats = 8,    // a periodic loop's timing
  kBenchSample = 9,  // `afhub bench` pings and pongs
  kDeviceState = 10,
  kDeviceCommand = 11,
  kSceneDescription = 12,  // what a viewer draws, published once by the physics
  kSoftBodyMesh = 13,      // a soft body's faces (once) or node positions (display rate)
  kScenePoses = 14,        // every body's pose for a viewer, at display rate
  kBenchSlot = 15,         // `afhub bench` pings and pongs through slots (afhub-slot)
  kStepTape = 16,          // a physics' states, commands taken, world state of a step, queued
};

struct PayloadHeader {
  std::uint64_t layout_id{0};  // kLayoutId of the build that wrote it
  PayloadKind kind{};
  std::uint32_t publisher_pid{0};
  std::uint64_t sequence{0};  // per publisher, starts at 1, +1 per publish
  std::uint64_t sim_step{0};  // state: step it describes; command: step it answers
  double sim_time_s{0.0};
  // monotonic_ns(), the same clock in every process: when the payload was published, or
  // for a physics' body states, when the step's publishing began (one stamp a step).
  std::int64_t publish_stamp_ns{0};
};

// The clock of every stamp and deadline in afhub: CLOCK_MONOTONIC, in nanoseconds.
inline std::int64_t monotonic_ns() noexcept {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

}  // namespace afhub
