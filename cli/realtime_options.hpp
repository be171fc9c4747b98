// --fifo, --cpu, --lock-memory and --cpu-wake-latency: how every 1 kHz loop (run, ctl,
// teleop, device run) asks this machine for real-time service (rt/periodic_loop.hpp).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "afhub/rt/periodic_loop.hpp"

namespace afhub::cli {

struct RealtimeOptions {
  int fifo_priority = 0;
  int cpu = -1;
  bool lock_memory = false;
  int cpu_wake_latency_us = -1;         // -1: leave the CPUs as they are
  bool cpu_wake_latency_given = false;  // written (then -1 is refused)
};

// `loop` names the loop in the help ("the loop", "the physics loop").
void add_realtime_options(CLI::App* command, RealtimeOptions& options, const std::string& loop);

// Checks them (afhub::Error naming the option) and sets them on `loop`.
void set_realtime_options(const RealtimeOptions& options, LoopOptions& loop);

}  // namespace afhub::cli
