// `afhub bench wake`: a 1 kHz periodic loop's wake-up latency (rt/periodic_loop.hpp)
// under each real-time setting its options give: the normal scheduler with the
// kernel's timer slack and with afhub's, SCHED_FIFO, each with and without holding
// the CPU wake-up latency limit. Each setting runs in a process of its own (a limit
// lasts as long as the process that holds it), in interleaved rounds, so that every
// setting sees the same moments of the machine.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "afhub/bench/distribution.hpp"

namespace afhub::bench {

struct WakeSetting {
  std::string name;  // as the options read: "--fifo 80 --cpu-wake-latency 0"
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
  // Rounds of the settings that hold no limit during which another process held the
  // machine's limit below 1 ms (those rounds measured a polling machine).
  std::uint32_t rounds_with_foreign_limit = 0;
};

// Runs every setting, with progress on stderr. Throws afhub::Error.
WakeResults run_wake_bench(const WakeOptions& options);

// One setting's loop, as the process run_wake_bench starts: prints "refused" when a
// setting's request was refused, else each cycle's wake-up latency in us, a line each.
int run_wake_peer(std::size_t setting, double seconds);

std::string wake_table(const WakeResults& results);

}  // namespace afhub::bench
