// The real-time options of the loops (see realtime_options.hpp).
#include "realtime_options.hpp"

#include "afhub/rt/cpu_wake_latency.hpp"
#include "afhub/shm_layout/error.hpp"

namespace afhub::cli {

void add_realtime_options(CLI::App* command, RealtimeOptions& options, const std::string& loop) {
  command->add_option(
      "--fifo", options.fifo_priority,
      "Run " + loop + " under SCHED_FIFO at this priority (1-99); says so if refused");
  command->add_option("--cpu", options.cpu, "Pin " + loop + " to this CPU");
  command->add_flag("--lock-memory", options.lock_memory,
                    "mlockall and pre-fault, so " + loop + " takes no page faults");
  command
      ->add_option("--cpu-wake-latency", options.cpu_wake_latency_us,
                   "Hold this machine's CPU wake-up latency limit at this many microseconds "
                   "while running (/dev/cpu_dma_latency, as cyclictest does; 0 to " +
                       std::to_string(kMaxCpuWakeLatencyUs) +
                       "): at 0 idle CPUs poll instead of sleeping, so " + loop +
                       " wakes on time, at the cost of busy idle cores. Needs root; says "
                       "so if refused")
      ->each([&options](const std::string&) { options.cpu_wake_latency_given = true; });
}

void set_realtime_options(const RealtimeOptions& options, LoopOptions& loop) {
  if (options.fifo_priority < 0 || options.fifo_priority > 99)
    throw Error("--fifo takes a SCHED_FIFO priority from 1 to 99");
  check_cpu_wake_latency_option(options.cpu_wake_latency_us, options.cpu_wake_latency_given);
  loop.fifo_priority = options.fifo_priority;
  loop.cpu = options.cpu;
  loop.lock_memory = options.lock_memory;
  loop.cpu_wake_latency_us = options.cpu_wake_latency_us;
}

}  // namespace afhub::cli
