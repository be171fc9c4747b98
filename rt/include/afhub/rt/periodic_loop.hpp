// A periodic loop for hard-real-time work at 1 kHz: paced by absolute deadlines
// (clock_nanosleep TIMER_ABSTIME on start + k * period, never re-based on now, so
// it does not drift), optionally under SCHED_FIFO, pinned to a CPU and with memory
// locked. A cycle that runs past later deadlines skips those periods and counts
// them as overruns: the loop stays on its grid instead of bursting to catch up.
#pragma once

#include <cstdint>
#include <functional>

#include "afhub/rt/loop_stats_publisher.hpp"
#include "afhub/rt/loop_timing.hpp"

namespace afhub {

struct LoopOptions {
  std::int64_t period_ns = 1'000'000;
  int fifo_priority = 0;         // 1..99: SCHED_FIFO at this priority; 0: the normal scheduler
  int cpu = -1;                  // pin the loop's thread to this CPU; -1: any
  bool lock_memory = false;      // mlockall and pre-fault the stack: no page faults in the loop
  std::uint64_t max_cycles = 0;  // stop after this many cycles; 0: until a stop signal
  // A point of the grid (CLOCK_MONOTONIC ns): cycles wake at grid_origin_ns + k * period.
  // 0: the grid starts one period from now.
  std::int64_t grid_origin_ns = 0;
};

// Applies the options to the calling thread; refusals are reported naming `who`.
RealtimeGrant apply_realtime(const LoopOptions& options, const char* who);

// Calls `cycle` once per period until it returns false, options.max_cycles or a
// stop signal. Each cycle's wake-up latency and compute time go into `timing`;
// `after` (optional) runs once per cycle outside the measured compute time, with
// the current CLOCK_MONOTONIC time: publish statistics there.
void run_periodic(const LoopOptions& options, LoopTiming& timing,
                  const std::function<bool()>& cycle,
                  const std::function<void(std::int64_t now_ns)>& after = {});

}  // namespace afhub
