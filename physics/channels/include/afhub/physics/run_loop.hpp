// The physics loop of `afhub run`: a fixed step, paced in real time on rt's loop
// runner by absolute deadlines (start + k * dt, never re-based, so there is no
// drift; late steps are caught up) or run as fast as possible; commands in and states out through
// SimChannels when given; world commands (pause, resume, step, reset) obeyed; in lockstep, each
// step waits for the lockstep clients' answers. Measures what the report needs.
#pragma once

#include <cstdint>
#include <string>

#include "afhub/physics/sim_channels.hpp"
#include "afhub/physics/simulation.hpp"
#include "afhub/rt/latency_histogram.hpp"
#include "afhub/rt/loop_stats_publisher.hpp"
#include "afhub/rt/loop_timing.hpp"

namespace afhub::physics {

struct RunOptions {
  bool fast = false;
  std::uint64_t steps = 0;  // stop after this many steps; 0: until a stop signal
  RealtimeGrant grant;      // what the loop's thread was granted, for its loop stats
};

struct RunReport {
  std::uint64_t steps = 0;
  double wall_time_s = 0.0;
  LatencyHistogram step_time;  // one loop iteration: step and publish (after the commands)
  LoopTiming timing;           // wake-up lateness, work time, overruns, late lockstep answers
  bool nan_detected = false;
  double max_joint_error_m = 0.0;  // the largest pivot gap seen, over all joints and steps
};

// Runs until options.steps, a stop signal or a NaN (then report.nan_detected).
void run_loop(Simulation& sim, SimChannels* channels, const RunOptions& options, RunReport& report);

// The --report JSON: steps, times, step-time percentiles, NaN flag, largest
// pivot gap, final body poses and joint positions. Keys are sorted.
std::string report_json(const RunReport& report, const Simulation& sim);

}  // namespace afhub::physics
