// The periodic loop (see periodic_loop.hpp).
#include "afhub/rt/periodic_loop.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <utility>

#include "afhub/rt/clock.hpp"
#include "afhub/rt/cpu_wake_latency.hpp"
#include "afhub/rt/stop_signal.hpp"

namespace afhub {
namespace {

// Touches this much stack once, so that the pages are resident before the loop.
void prefault_stack() {
  constexpr std::size_t kBytes = 256 * 1024;
  char stack[kBytes];
  volatile char* page = stack;
  for (std::size_t i = 0; i < kBytes; i += 4096) page[i] = 0;
}

}  // namespace

RealtimeGrant apply_realtime(const LoopOptions& options, const char* who) {
  RealtimeGrant grant;
  if (options.lock_memory) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      prefault_stack();
      grant.memory_locked = true;
    } else {
      std::fprintf(stderr,
                   "%s: cannot lock memory (%s); running without: page faults may add latency. "
                   "Raise `ulimit -l` or run with CAP_IPC_LOCK\n",
                   who, std::strerror(errno));
    }
  }
  if (options.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(options.cpu, &set);
    const int error = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
    if (error == 0)
      grant.cpu = options.cpu;
    else
      std::fprintf(stderr, "%s: cannot pin to CPU %d (%s); running on any CPU\n", who, options.cpu,
                   std::strerror(error));
  }
  // Per thread; 0 restores the thread's default.
  prctl(PR_SET_TIMERSLACK, static_cast<unsigned long>(options.timer_slack_ns));
  if (options.cpu_wake_latency_us >= 0 && hold_cpu_wake_latency(options.cpu_wake_latency_us, who))
    grant.cpu_wake_latency_us = options.cpu_wake_latency_us;
  if (options.fifo_priority > 0) {
    sched_param param{};
    param.sched_priority = options.fifo_priority;
    const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
    if (error == 0)
      grant.realtime = true;
    else
      std::fprintf(stderr,
                   "%s: cannot use SCHED_FIFO priority %d (%s); running under the normal "
                   "scheduler. Run as root, with CAP_SYS_NICE, or raise `ulimit -r`\n",
                   who, options.fifo_priority, std::strerror(error));
  }
  return grant;
}

namespace {

class MonotonicClock final : public LoopClock {
 public:
  std::int64_t now_ns() noexcept override { return monotonic_ns(); }
  void sleep_until_ns(std::int64_t deadline_ns) noexcept override {
    afhub::sleep_until_ns(deadline_ns);
  }
};

// The first deadline after `now`: the grid's origin when it is ahead, else the grid's
// next point; with no origin, one period from now.
std::int64_t first_deadline(std::int64_t origin, std::int64_t period, std::int64_t now) {
  if (origin > now) return origin;
  if (origin > 0 && period > 0) return origin + ((now - origin) / period + 1) * period;
  return now + period;
}

}  // namespace

void run_periodic(const LoopOptions& options, LoopTiming& timing, const LoopCycle& cycle) {
  MonotonicClock monotonic;
  LoopClock& clock = options.clock ? *options.clock : monotonic;
  const std::int64_t period = options.period_ns;
  std::int64_t scheduled = first_deadline(options.grid_origin_ns, period, clock.now_ns());
  for (std::uint64_t done = 0;
       !stop_requested() && (options.max_cycles == 0 || done < options.max_cycles); ++done) {
    if (period > 0) clock.sleep_until_ns(scheduled);
    if (cycle.deadline_ns) *cycle.deadline_ns = scheduled;
    const std::int64_t woke = clock.now_ns();
    if (cycle.wait && !cycle.wait()) break;
    const std::int64_t began = clock.now_ns();
    const bool go_on = cycle.work();
    const std::int64_t finished = clock.now_ns();
    const std::int64_t waited = cycle.waited_ns ? std::exchange(*cycle.waited_ns, 0) : 0;
    timing.record(period > 0 ? woke - scheduled : 0, finished - began - waited);
    scheduled += period;
    if (period > 0 && finished >= scheduled) {
      if (options.overrun == OverrunPolicy::kSkip) {
        // Past the next deadline already: skip the periods missed, stay on the grid.
        const std::int64_t missed = (finished - scheduled) / period + 1;
        timing.count_overruns(static_cast<std::uint64_t>(missed));
        scheduled += missed * period;
      } else if (finished - scheduled > options.max_catch_up_ns) {
        // Stopped for longer than is worth making up: the periods beyond are skipped.
        const std::int64_t missed = (finished - scheduled) / period + 1;
        timing.count_overruns(static_cast<std::uint64_t>(missed));
        scheduled += missed * period;
      } else {
        // Behind: the next cycles run at once, back to back, until caught up.
        timing.count_overruns(1);
      }
    }
    if (cycle.regrid_ns && *cycle.regrid_ns > 0) {
      scheduled = first_deadline(*cycle.regrid_ns, period, clock.now_ns());
      *cycle.regrid_ns = 0;
    }
    if (cycle.after) {
      const std::int64_t after_began = clock.now_ns();
      cycle.after(after_began);
      timing.record_housekeeping(clock.now_ns() - after_began);
    }
    if (!go_on) break;
  }
}

void run_periodic(const LoopOptions& options, LoopTiming& timing,
                  const std::function<bool()>& cycle,
                  const std::function<void(std::int64_t)>& after) {
  run_periodic(options, timing, LoopCycle{{}, cycle, after});
}

}  // namespace afhub
