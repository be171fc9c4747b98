// The 1 kHz loop: `afhub run` simulates the model in real time; this process runs
// a controller at 1 kHz on the model's body (holding its joints), in phase with the
// physics as every controller is by default (half a period after each step is due);
// cyclictest runs beside it, at the same priority
// and over the same seconds, as the machine's floor. Measured: the controller's
// wake-up latency, cyclictest's, and the share of steps whose command answered the
// state published just before (from the physics' own counters).
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>

#include "afhub/bench/bench.hpp"
#include "afhub/controllers/controller.hpp"
#include "afhub/controllers/joint_targets.hpp"
#include "afhub/hub/channel.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/process_spawn.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/world.hpp"
#include "child_process.hpp"

namespace afhub::bench {
namespace {

constexpr std::int64_t kControllerPeriodNs = 1'000'000;

// cyclictest -h output: "# Histogram", one "bin count" line per microsecond, then
// "# Max Latencies: N" and "# Histogram Overflows: N".
void read_cyclictest(const std::string& path, LoopResult& result) {
  std::ifstream in(path);
  std::uint64_t overflows = 0;
  std::int64_t max_us = 0;
  for (std::string line; std::getline(in, line);) {
    unsigned long long bin = 0, count = 0;
    if (std::sscanf(line.c_str(), "%llu %llu", &bin, &count) == 2) {
      result.cyclictest_wake.record(static_cast<std::int64_t>(bin) * 1000, count);
    } else if (std::sscanf(line.c_str(), "# Max Latencies: %llu", &bin) == 1) {
      max_us = static_cast<std::int64_t>(bin);
    } else if (std::sscanf(line.c_str(), "# Histogram Overflows: %llu", &count) == 1) {
      overflows = count;
    }
  }
  // Samples beyond cyclictest's histogram count at its maximum, which is exact.
  result.cyclictest_wake.record(max_us * 1000, overflows);
  if (result.cyclictest_wake.count() == 0)
    throw Error("cyclictest wrote no histogram to " + path + ": see that file");
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

void run_loop_bench(const BenchOptions& options, LoopResult& result) {
  result.seconds = options.loop_seconds;
  connect_to_hub("bench", HubPolicy::kRequire);
  const std::string prefix = "/tmp/afhub-bench-" + std::to_string(getpid());
  const std::string priority = std::to_string(options.fifo_priority);
  std::fprintf(stderr, "afhub bench: 1 kHz loop for %.0f s against %s\n", options.loop_seconds,
               options.model.c_str());
  // Its step log holds every step of the run (the physics is stopped once the loop is
  // done): it tells the late commands apart.
  const struct StepLogFile {
    std::string path;
    ~StepLogFile() {
      std::error_code ignored;
      std::filesystem::remove(path, ignored);
    }
  } step_log{prefix + "-steps.txt"};  // removed however the run ends, after the physics
  const auto log_steps = static_cast<std::uint64_t>((options.loop_seconds + 120.0) * 1000.0);
  ChildProcess physics(
      {this_executable(), "run", options.model, "--no-autostart", "--fifo", priority,
       "--lock-memory", "--steps", std::to_string(log_steps), "--step-log", step_log.path},
      prefix + "-physics.log");

  const auto cycles = static_cast<std::uint64_t>(options.loop_seconds * 1e9 / kControllerPeriodNs);
  std::unique_ptr<ChildProcess> cyclictest;
  if (access("/usr/bin/cyclictest", X_OK) == 0)
    cyclictest = std::make_unique<ChildProcess>(
        std::vector<std::string>{"cyclictest", "-m", "-q", "-p", priority, "-i", "1000", "-l",
                                 std::to_string(cycles), "-h", "20000"},
        prefix + "-cyclictest.txt");
  else
    result.cyclictest_skipped = "cyclictest not found: install Debian's rt-tests";

  LatestReader<WorldState> world(
      {std::string(kService), std::string(kWorldInstance), std::string(kStateEvent)});
  ControllerOptions controller;
  controller.name = "bench";
  controller.body = options.body;
  controller.loop.period_ns = kControllerPeriodNs;
  controller.loop.fifo_priority = options.fifo_priority;
  controller.loop.lock_memory = true;
  controller.loop.max_cycles = cycles;
  LoopTiming timing;
  // The counters at the start are read on the first cycle, once the physics runs.
  bool started = false;
  std::int64_t started_ns = 0;
  std::uint64_t commanded_before = 0, answered_before = 0;
  const ControllerCycle hold = joint_position_controller(hold_targets());
  const auto cycle = [&](const BodyState& state, BodyCommand& command) {
    if (!started)
      if (const WorldState* now = world.latest()) {
        commanded_before = now->commanded_steps;
        answered_before = now->answered_steps;
        started = true;
        started_ns = monotonic_ns();
      }
    hold(state, command);
  };
  try {
    run_controller(controller, cycle, &timing);
  } catch (const Error& error) {
    if (physics.running()) throw;
    // Its body never came: what the physics said is the reason.
    throw Error(std::string(error.what()) + "\nThe physics ended (exit code " +
                std::to_string(physics.wait(0)) + "); it said:\n" +
                read_text(prefix + "-physics.log"));
  }
  const std::int64_t finished_ns = monotonic_ns();
  if (const WorldState* now = world.latest()) {
    result.commanded_steps = now->commanded_steps - commanded_before;
    result.answered_steps = now->answered_steps - answered_before;
  }
  if (stop_requested()) throw Error("interrupted");  // cyclictest runs on: not waited for
  result.controller_wake = timing.wake_latency();
  physics.stop(kPhysicsStopMs);  // SIGTERM: it writes its step log, then exits
  result.physics_dropped = first_line_with(prefix + "-physics.log", "shared memory exhausted");
  std::filesystem::remove(prefix + "-physics.log");
  result.late = late_commands(read_step_log(step_log.path, started_ns, finished_ns));
  if (cyclictest) {
    if (cyclictest->wait(10'000) == -1)
      throw Error("cyclictest did not finish 10 s after the loop; see " + prefix +
                  "-cyclictest.txt");
    read_cyclictest(prefix + "-cyclictest.txt", result);
    std::filesystem::remove(prefix + "-cyclictest.txt");
  }
}

}  // namespace afhub::bench
