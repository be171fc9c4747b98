// --rate, --cycles and the real-time options (realtime_options.hpp): how each periodic
// loop of the command line (ctl, teleop, device run, device force) is paced.
#pragma once

#include <optional>

#include <CLI/CLI.hpp>
#include <cstdint>

#include "afhub/hub/step_phase.hpp"
#include "afhub/rt/periodic_loop.hpp"
#include "realtime_options.hpp"

namespace afhub::cli {

struct LoopRateOptions {
  double rate_hz = 1000.0;
  std::uint64_t cycles = 0;  // 0: until Ctrl-C
  RealtimeOptions realtime;
};

void add_loop_rate_options(CLI::App* command, LoopRateOptions& options);

// Checks them (afhub::Error naming the option) and sets them on `loop`.
void set_loop_rate_options(const LoopRateOptions& options, LoopOptions& loop);

// --after-step and --unaligned: when a loop reading a body wakes against its physics'
// steps (afhub/hub/step_phase.hpp), for ctl's controllers and teleop.
struct PhaseOptions {
  std::optional<double> after_step_us;  // none: half the period
  bool unaligned = false;
};

void add_phase_options(CLI::App* command, PhaseOptions& options, const char* what);

// Checks them against the loop's period (afhub::Error naming the option) and gives the
// loop's after_step_ns: an offset, kAfterStepHalfPeriod or kAfterStepUnaligned.
std::int64_t after_step_ns(const PhaseOptions& options, std::int64_t period_ns);

}  // namespace afhub::cli
