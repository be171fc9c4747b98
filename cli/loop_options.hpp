// --rate, --cycles and the real-time options (realtime_options.hpp): how each periodic
// loop of the command line (ctl, teleop, device run, device force) is paced.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>

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

}  // namespace afhub::cli
