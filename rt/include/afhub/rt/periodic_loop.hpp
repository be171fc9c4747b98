// A periodic loop for hard-real-time work at 1 kHz: paced by absolute deadlines
// (clock_nanosleep TIMER_ABSTIME on start + k * period, never re-based on now, so
// it does not drift), optionally under SCHED_FIFO, pinned to a CPU and with memory
// locked. What a cycle that runs past later deadlines does is the overrun policy:
// a controller skips those periods (it stays on its grid), the physics catches up
// (its late steps run back to back, so that simulated time keeps up with the wall).
// A period of 0 runs the cycles back to back, as fast as possible.
#pragma once

#include <cstdint>
#include <functional>

#include "afhub/rt/loop_timing.hpp"

namespace afhub {

// What the system granted a loop's real-time requests (SCHED_FIFO, mlockall, CPU).
struct RealtimeGrant {
  bool realtime = false;
  bool memory_locked = false;
  int cpu = -1;
  int cpu_wake_latency_us = -1;  // the wake-up latency limit held, or -1
};

enum class OverrunPolicy {
  // Stay on the grid: the periods a cycle ran past are skipped and counted as
  // overruns (controllers: a late command is worth less than the next one on time).
  kSkip,
  // Catch up: the cycles whose deadlines passed run back to back until the loop is
  // on time again; each cycle that ends past the next deadline counts as an overrun
  // (the physics: 10 s of wall time are 10 000 steps of 1 ms). Up to
  // LoopOptions::max_catch_up_ns behind: a loop stopped longer (a debugger, SIGSTOP,
  // a VM pause) skips what is beyond, as kSkip does, rather than burst through it.
  kCatchUp,
};

// The clock a loop paces itself by. By default (LoopOptions::clock null) it is
// monotonic_ns() and clock_nanosleep to an absolute deadline; a test injects its own
// to check the pacing exactly, whatever the load of the machine it runs on.
class LoopClock {
 public:
  virtual ~LoopClock() = default;
  virtual std::int64_t now_ns() noexcept = 0;
  virtual void sleep_until_ns(std::int64_t deadline_ns) noexcept = 0;
};

// The rates a loop is given from outside (the command line, Python): a period up to
// 1000 s (past an int64 of nanoseconds, at 1e-10 Hz, it came out negative and the loop
// spun), down to 10 us (a loop's own work is about that).
inline constexpr double kMinLoopRateHz = 0.001;
inline constexpr double kMaxLoopRateHz = 100'000.0;

struct LoopOptions {
  std::int64_t period_ns = 1'000'000;  // 0: as fast as possible (no sleeping, no overruns)
  OverrunPolicy overrun = OverrunPolicy::kSkip;
  int fifo_priority = 0;     // 1..99: SCHED_FIFO at this priority; 0: the normal scheduler
  int cpu = -1;              // pin the loop's thread to this CPU; -1: any
  bool lock_memory = false;  // mlockall and pre-fault the stack: no page faults in the loop
  // 0..kMaxCpuWakeLatencyUs: hold the machine's CPU wake-up latency limit at this while the
  // process runs (cpu_wake_latency.hpp; 0: idle CPUs poll, so the loop wakes on time); -1:
  // leave the CPUs as they are.
  int cpu_wake_latency_us = -1;
  // How late the kernel may end the loop's timed sleeps to merge timer wake-ups (its
  // "timer slack"). Linux gives a thread 50 us, which lands on every wake-up of a loop
  // under the normal scheduler (SCHED_FIFO ignores it); 0: the thread's default (its
  // creator's slack when it was made, 50 us unless something changed it).
  std::int64_t timer_slack_ns = 1;
  std::uint64_t max_cycles = 0;  // stop after this many cycles; 0: until a stop signal
  // A point of the grid (CLOCK_MONOTONIC ns): cycles wake at grid_origin_ns + k * period.
  // 0: the grid starts one period from now.
  std::int64_t grid_origin_ns = 0;
  LoopClock* clock = nullptr;  // null: the real monotonic clock
  // kCatchUp: the most a loop makes up; further behind, it skips to the grid.
  std::int64_t max_catch_up_ns = 100'000'000;
};

// Applies the options to the calling thread; refusals are reported naming `who`.
RealtimeGrant apply_realtime(const LoopOptions& options, const char* who);

// What a periodic loop runs each cycle, in this order.
struct LoopCycle {
  // Optional and untimed: waiting for something other than the clock once awake
  // (a lockstep barrier). False ends the loop at once.
  std::function<bool()> wait;
  // The cycle's work, timed as its compute time. False ends the loop after `after`.
  std::function<bool()> work;
  // Optional, outside the measured time, with the current CLOCK_MONOTONIC time:
  // publish statistics there.
  std::function<void(std::int64_t now_ns)> after;
  // Optional: each cycle's deadline is written here before it runs (on the loop's
  // clock; the physics stamps its steps with it).
  std::int64_t* deadline_ns = nullptr;
  // Optional: how long the work waited for something (a controller following a
  // catching-up physics, step by step), written by the work: left out of its compute
  // time, and set back to 0.
  std::int64_t* waited_ns = nullptr;
  // Optional: a grid point the cycle writes here (a controller following a restarted
  // physics' phase): the loop keeps to that grid from the next cycle on, and sets it
  // back to 0.
  std::int64_t* regrid_ns = nullptr;
};

// Runs `cycle` once per period until its work returns false, options.max_cycles or
// a stop signal. Each cycle's wake-up latency (from its deadline to the wake-up)
// and compute time (its work) go into `timing`, with the overruns.
void run_periodic(const LoopOptions& options, LoopTiming& timing, const LoopCycle& cycle);

// The same with no wait: `cycle` is the work.
void run_periodic(const LoopOptions& options, LoopTiming& timing,
                  const std::function<bool()>& cycle,
                  const std::function<void(std::int64_t now_ns)>& after = {});

}  // namespace afhub
