// `afhub bench wake`: a 1 kHz periodic loop's wake-up latency (rt/periodic_loop.hpp)
// under five real-time settings its options give: the normal scheduler with the
// thread's default timer slack, with afhub's 1 ns, and holding the CPU wake-up latency
// limit at 0; SCHED_FIFO without and with that limit. Each setting runs in a process of its own (a
// limit lasts as long as the process that holds it), in interleaved rounds, so that every setting
// sees the same moments of the machine.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "afhub/bench/distribution.hpp"

namespace afhub::bench {

struct WakeSetting {
  std::string name;  // as the table shows it
  int fifo_priority = 0;
  int cpu_wake_latency_us = -1;
  std::int64_t timer_slack_ns = 1;
};

const std::vector<WakeSetting>& wake_settings();

struct WakeOptions {
  std::uint32_t rounds = 10;
  double seconds = 1.0;  // per setting and round
};

struct WakeResult {
  WakeSetting setting;
  std::string skipped;  // why it did not run (refused); empty when it ran
  Distribution wake;
};

struct WakeResults {
  WakeOptions options;
  std::vector<WakeResult> settings;
  // Rounds at the start of which another process held the machine's limit (read
  // before each setting that holds none; root only), and the lowest limit seen.
  std::uint32_t rounds_with_foreign_limit = 0;
  std::int32_t foreign_limit_us = -1;
};

// Runs every setting, with progress on stderr. Throws afhub::Error.
WakeResults run_wake_bench(const WakeOptions& options);

// One setting's loop, as the process run_wake_bench starts. Prints "refused: WHY" when
// the system refused the setting; else "max US" (the exact maximum), then "BIN COUNT"
// for each non-empty 1 us bin of its wake-up latencies.
int run_wake_peer(std::size_t setting, double seconds);

std::string wake_table(const WakeResults& results);

}  // namespace afhub::bench
