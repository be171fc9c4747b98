// `afhub bench`: end-to-end latency of afhub's channels beside the transports users
// would otherwise pick (Cyclone DDS, Unix sockets, ROS 1), and the jitter of a 1 kHz
// controller against a running physics beside the machine's floor (cyclictest).
// The method is in docs/bench.md.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "afhub/bench/distribution.hpp"
#include "afhub/bench/step_log.hpp"

namespace afhub::bench {

// The payload sizes measured, in bytes.
inline const std::vector<std::uint32_t> kPayloadSizes = {64, 1024, 16384, 262144, 1048576};

struct BenchOptions {
  std::vector<std::string> transports = {"afhub",   "afhub-slot", "shm-floor", "dds",
                                         "dds-shm", "uds",        "ros1"};
  std::uint32_t rounds = 20;            // interleaved rounds over every transport and size
  std::uint32_t pings_per_round = 500;  // round trips per transport, size and round
  std::uint32_t warmup_pings = 200;     // per transport and size, before the first round
  double loop_seconds = 60.0;           // the 1 kHz loop; 0: skip it
  std::string model;                    // the physics the loop runs against
  std::string body = "base";            // the body its controller commands
  int fifo_priority = 80;               // the loop's and cyclictest's SCHED_FIFO priority
  // Every byte of a message written by its sender and read by its receiver, rather than
  // the stamps alone (see Transport::set_touch).
  bool touch = false;
};

// --quick: a few minutes' worth instead of a quarter of an hour's.
BenchOptions quick_options(BenchOptions options);

struct MachineInfo {
  std::string cpu, kernel, os, date;
  unsigned cores = 0;
  double memory_gib = 0.0;
};

struct TransportResult {
  std::string name;
  std::string skipped;  // why it did not run; empty when it ran
  // Per payload size: one-way latencies (both directions) and round trips, in us.
  std::map<std::uint32_t, std::vector<double>> one_way_us, round_trip_us;
};

struct LoopResult {
  std::string skipped;  // why the loop did not run; empty when it ran
  double seconds = 0.0;
  LatencyHistogram controller_wake;  // the afhub controller's wake-up latency
  std::string cyclictest_skipped;
  LatencyHistogram cyclictest_wake;  // its maximum exact, as cyclictest reports it
  std::uint64_t commanded_steps = 0, answered_steps = 0;
  LateCommands late;  // from the physics' step log
  // What the physics said when it could not publish a state (a pool out of chunks):
  // empty when it published every step.
  std::string physics_dropped;
  double deadline_hit_ratio() const {
    return commanded_steps ? static_cast<double>(answered_steps) / commanded_steps : 0.0;
  }
};

struct BenchResults {
  MachineInfo machine;
  BenchOptions options;
  std::vector<TransportResult> transports;
  LoopResult loop;
};

MachineInfo read_machine_info();

// The hub the bench runs against. When none runs: `afhub hub --bench-pools`, stopped
// when the bench exits, after its iceoryx runtime has left the hub (and by its
// parent-death signal if the bench is killed): the next program the user runs must
// not land on a hub with the bench's pools. A running hub is used as it is (the afhub
// transport checks its pools). Call before anything connects to a hub.
void start_bench_hub_if_none();
// Runs everything, with progress on stderr. Throws afhub::Error.
void run_ping_pong(const BenchOptions& options, BenchResults& results);
void run_loop_bench(const BenchOptions& options, LoopResult& result);

// The pong side of the ping-pong, as the peer process the bench starts.
int run_peer(const std::string& transport, const std::string& session, int cpu, bool touch);

// The outputs: the --json document, the table for stdout, the --plot PNG (gnuplot).
std::string results_json(const BenchResults& results);
std::string results_table(const BenchResults& results);
// Why the run does not stand for afhub at work, one line each: the physics dropped
// states, or fewer than kMinInTimeRatio of the commands came in time for the next step.
inline constexpr double kMinInTimeRatio = 0.9;
// Issue 30's goal for a controller in phase with the physics, beside cyclictest.
inline constexpr double kInTimeGoal = 0.99;
std::vector<std::string> failures(const BenchResults& results);
void write_plot(const BenchResults& results, const std::string& png_path);
// A loop's wake-up histogram as the plot draws it: (upper edge in us, count) per bin up
// to the maximum's. Above 128 us a bin is 1/128 of a power of two, as wide on the log
// scale as its neighbours; below, bins are merged into whole microseconds, cyclictest's
// resolution (finer, its counts fall in one bin of several and its curve vanishes).
std::vector<std::pair<double, std::uint64_t>> histogram_rows(const LatencyHistogram& h);

}  // namespace afhub::bench
