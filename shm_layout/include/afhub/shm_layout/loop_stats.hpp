// LoopStats: what a periodic loop (a controller, a device driver) publishes about
// its own timing once a second, for `afhub status` and `afhub top`.
#pragma once

#include <array>
#include <cstdint>

#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

// Percentiles of a duration since the loop started, in microseconds.
struct DurationPercentiles {
  double p50_us{0.0};
  double p99_us{0.0};
  double p999_us{0.0};
  double max_us{0.0};
};

struct LoopStats {
  static constexpr PayloadKind kKind = PayloadKind::kLoopStats;
  PayloadHeader header;
  std::array<char, kChannelNameBufferSize> name{};  // what the loop does: "ctl sine"
  std::array<char, kChannelNameBufferSize> body{};  // the body it commands, if any
  double period_s{0.0};
  double rate_hz{0.0};  // cycles per second over the last second
  std::uint64_t cycles{0};
  std::uint64_t overruns{0};  // periods skipped because a cycle ran past them
  // Free-running: commands computed from a state the physics had already replaced
  // when the command was written. Lockstep: steps taken without this loop's answer.
  std::uint64_t late_commands{0};
  DurationPercentiles wake_latency;  // actual wake-up minus scheduled (0 in lockstep)
  DurationPercentiles compute;       // wake-up to command written
  std::uint8_t realtime{0};          // running under SCHED_FIFO
  std::uint8_t memory_locked{0};     // mlockall succeeded
  std::uint8_t lockstep{0};
  std::uint8_t reserved{0};
  std::int32_t cpu{-1};                  // pinned CPU, or -1
  std::int32_t cpu_wake_latency_us{-1};  // the CPU wake-up latency limit it holds, or -1
};

}  // namespace afhub
