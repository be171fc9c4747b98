// The periodic loop: pacing without drift, overruns skipped or caught up and
// counted, as fast as possible with no period, a wait before the work, and the
// loop statistics read from known histogram contents.
#include "afhub/rt/periodic_loop.hpp"

#include <gtest/gtest.h>
#include <sys/prctl.h>

#include <algorithm>
#include <functional>

#include <string>
#include <thread>
#include <vector>

#include "afhub/rt/clock.hpp"
#include "afhub/rt/stop_signal.hpp"

namespace afhub {
namespace {

// The pacing is checked on a clock the test drives, never on this shared machine's
// wall clock: sleeping jumps to the deadline plus a lateness the test chooses (a
// loaded machine wakes late), and a cycle's work advances the clock by what the
// test says it takes. Every deadline the loop asks for is recorded.
class FakeClock final : public LoopClock {
 public:
  std::int64_t now = 1'000'000'000'000;
  std::vector<std::int64_t> deadlines;  // each sleep's deadline, in order
  std::vector<std::int64_t> woke;       // when each sleep returned
  // How late the n-th wake-up is (ns); none by default.
  std::function<std::int64_t(std::size_t)> lateness = [](std::size_t) { return 0; };

  FakeClock() {
    deadlines.reserve(1000);
    woke.reserve(1000);
  }
  std::int64_t now_ns() noexcept override { return now; }
  void sleep_until_ns(std::int64_t deadline_ns) noexcept override {
    deadlines.push_back(deadline_ns);
    now = std::max(now, deadline_ns) + lateness(deadlines.size() - 1);
    woke.push_back(now);
  }
};

// A machine's noise: wake-ups late by 0 to `max_ns`, varying from cycle to cycle.
std::function<std::int64_t(std::size_t)> noisy(std::int64_t max_ns) {
  return [max_ns](std::size_t n) {
    return static_cast<std::int64_t>((n * 7919) % 101) * max_ns / 100;
  };
}

TEST(PeriodicLoop, NPeriodsTakeNTimesThePeriodWithoutDrift) {
  // Every wake-up is up to 3 ms late and every cycle works 1 ms: a loop re-based on
  // "now + period" would drift by both each cycle; absolute deadlines do not.
  FakeClock clock;
  clock.lateness = noisy(3'000'000);
  LoopOptions options;
  options.period_ns = 5'000'000;
  options.max_cycles = 200;
  options.clock = &clock;
  LoopTiming timing;
  const std::int64_t start = clock.now;
  int cycles = 0;
  run_periodic(options, timing, [&] {
    ++cycles;
    clock.now += 1'000'000;
    return true;
  });
  EXPECT_EQ(cycles, 200);
  EXPECT_EQ(timing.cycles(), 200u);
  EXPECT_EQ(timing.overruns(), 0u);
  ASSERT_EQ(clock.deadlines.size(), 200u);
  EXPECT_EQ(clock.deadlines.front(), start + 5'000'000);
  for (std::size_t k = 0; k < clock.deadlines.size(); ++k)
    ASSERT_EQ(clock.deadlines[k], start + static_cast<std::int64_t>(k + 1) * 5'000'000) << k;
  // The wake-up latency is measured from each deadline: the chosen lateness, at most 3 ms.
  EXPECT_LE(timing.wake_latency().max_us(), 3000.0 + 1.0);
}

TEST(PeriodicLoop, WakeUpsStayOnTheGridDespiteSlowCycles) {
  // Every cycle works for 60% of a period and wakes up to 1 ms late.
  FakeClock clock;
  clock.lateness = noisy(1'000'000);
  LoopOptions options;
  options.period_ns = 5'000'000;
  options.max_cycles = 100;
  options.clock = &clock;
  LoopTiming timing;
  const std::int64_t start = clock.now;
  run_periodic(options, timing, [&] {
    clock.now += 3'000'000;
    return true;
  });
  EXPECT_EQ(timing.overruns(), 0u);
  ASSERT_EQ(clock.deadlines.size(), 100u);
  for (std::size_t k = 0; k < clock.deadlines.size(); ++k)
    ASSERT_EQ(clock.deadlines[k], start + static_cast<std::int64_t>(k + 1) * 5'000'000) << k;
  EXPECT_GE(timing.compute().percentile_us(0.5), 3000.0);
}

TEST(PeriodicLoop, AnOverrunSkipsTheMissedPeriodsAndCountsThem) {
  FakeClock clock;
  LoopOptions options;
  options.period_ns = 10'000'000;
  options.max_cycles = 20;
  options.clock = &clock;
  LoopTiming timing;
  int cycle = 0;
  run_periodic(options, timing, [&] {
    // Cycle 5 runs for 2.5 periods: the next two deadlines pass while it works.
    if (++cycle == 5) clock.now += 25'000'000;
    return true;
  });
  EXPECT_EQ(timing.cycles(), 20u);
  EXPECT_EQ(timing.overruns(), 2u);
  ASSERT_EQ(clock.deadlines.size(), 20u);
  // Skipped, not made up in a burst: cycle 6 wakes 3 periods after cycle 5, and the
  // 20 cycles span 19 + 2 periods.
  EXPECT_EQ(clock.deadlines[5] - clock.deadlines[4], 30'000'000);
  EXPECT_EQ(clock.deadlines.back() - clock.deadlines.front(), 21 * 10'000'000);
}

TEST(PeriodicLoop, CatchingUpRunsTheLateCyclesBackToBack) {
  FakeClock clock;
  LoopOptions options;
  options.period_ns = 10'000'000;
  options.max_cycles = 20;
  options.overrun = OverrunPolicy::kCatchUp;
  options.clock = &clock;
  LoopTiming timing;
  int cycle = 0;
  run_periodic(options, timing, [&] {
    // Cycle 5 runs for 2.5 periods: cycles 6 and 7 follow at once to make up for it.
    if (++cycle == 5) clock.now += 25'000'000;
    return true;
  });
  EXPECT_EQ(timing.cycles(), 20u);
  EXPECT_EQ(timing.overruns(), 2u);  // cycles 5 and 6 ended past the next deadline
  ASSERT_EQ(clock.deadlines.size(), 20u);
  // Made up, not skipped: 20 cycles span 19 periods, as if nothing had been late...
  for (std::size_t k = 1; k < clock.deadlines.size(); ++k)
    EXPECT_EQ(clock.deadlines[k] - clock.deadlines[k - 1], 10'000'000) << k;
  // ...and cycles 6 and 7 woke at once, when cycle 5 ended.
  EXPECT_EQ(clock.woke[5], clock.woke[4] + 25'000'000);
  EXPECT_EQ(clock.woke[6], clock.woke[5]);
  EXPECT_EQ(clock.woke[7], clock.deadlines[7]);
}

// A loop stopped for 5 s (SIGSTOP, a debugger) does not burst through 500 cycles
// when it resumes: it makes up nothing beyond max_catch_up_ns and stays on its grid.
TEST(PeriodicLoop, CatchingUpSkipsWhatIsBeyondTheBound) {
  FakeClock clock;
  LoopOptions options;
  options.period_ns = 10'000'000;
  options.max_cycles = 20;
  options.overrun = OverrunPolicy::kCatchUp;
  options.max_catch_up_ns = 100'000'000;
  options.clock = &clock;
  LoopTiming timing;
  int cycle = 0;
  run_periodic(options, timing, [&] {
    if (++cycle == 5) clock.now += 5'000'000'000;  // stopped for 5 s during cycle 5
    return true;
  });
  EXPECT_EQ(timing.cycles(), 20u);
  EXPECT_EQ(timing.overruns(), 500u);  // the 500 periods it was away, skipped
  ASSERT_EQ(clock.deadlines.size(), 20u);
  // Cycle 6 wakes on the grid after the stop, and every later one a period apart.
  EXPECT_EQ(clock.deadlines[5] - clock.deadlines[4], 501 * 10'000'000LL);
  EXPECT_GE(clock.deadlines[5], clock.woke[4] + 5'000'000'000);
  for (std::size_t k = 6; k < clock.deadlines.size(); ++k)
    EXPECT_EQ(clock.deadlines[k] - clock.deadlines[k - 1], 10'000'000) << k;
}

TEST(PeriodicLoop, PeriodZeroRunsAsFastAsPossible) {
  FakeClock clock;
  LoopOptions options;
  options.period_ns = 0;
  options.max_cycles = 100'000;
  options.clock = &clock;
  LoopTiming timing;
  run_periodic(options, timing, [] { return true; });
  EXPECT_EQ(timing.cycles(), 100'000u);
  EXPECT_EQ(timing.overruns(), 0u);
  EXPECT_TRUE(clock.deadlines.empty());  // it never slept
}

TEST(PeriodicLoop, TheWaitRunsFirstUntimedAndCanEndTheLoop) {
  FakeClock clock;
  LoopOptions options;
  options.period_ns = 1'000'000;
  options.clock = &clock;
  LoopTiming timing;
  std::vector<char> order;
  LoopCycle cycle;
  cycle.wait = [&] {
    order.push_back('w');
    clock.now += 5'000'000;  // waiting: not compute time
    return order.size() < 7;
  };
  cycle.work = [&] {
    order.push_back('c');
    clock.now += 100'000;
    return true;
  };
  cycle.after = [&](std::int64_t) { order.push_back('a'); };
  run_periodic(options, timing, cycle);
  EXPECT_EQ(std::string(order.begin(), order.end()), "wcawcaw");
  EXPECT_EQ(timing.cycles(), 2u);
  EXPECT_DOUBLE_EQ(timing.compute().max_us(), 100.0);
}

TEST(PeriodicLoop, AGivenGridOriginSetsThePhaseOfEveryWakeUp) {
  // The origin lies 2.3 periods in the past: wake-ups fall on origin + k * period,
  // 0.7 periods from now first, never on now + period.
  FakeClock clock;
  clock.lateness = noisy(2'000'000);
  LoopOptions options;
  options.period_ns = 10'000'000;
  options.max_cycles = 10;
  options.grid_origin_ns = clock.now - 23'000'000;
  options.clock = &clock;
  LoopTiming timing;
  run_periodic(options, timing, [] { return true; });
  ASSERT_EQ(clock.deadlines.size(), 10u);
  EXPECT_EQ(clock.deadlines.front(), options.grid_origin_ns + 30'000'000);
  for (std::int64_t at : clock.deadlines)
    EXPECT_EQ((at - options.grid_origin_ns) % options.period_ns, 0) << at;
  // A future origin is the first wake-up.
  options.max_cycles = 1;
  options.grid_origin_ns = clock.now + 35'000'000;
  clock.deadlines.clear();
  run_periodic(options, timing, [] { return true; });
  ASSERT_EQ(clock.deadlines.size(), 1u);
  EXPECT_EQ(clock.deadlines.front(), options.grid_origin_ns);
}

// The cycle learns its deadline; a new grid point written by a cycle moves the
// following wake-ups onto that grid (a controller following a restarted physics).
TEST(PeriodicLoop, ACycleReadsItsDeadlineAndCanMoveTheGrid) {
  FakeClock clock;
  clock.lateness = noisy(2'000'000);
  LoopOptions options;
  options.period_ns = 10'000'000;
  options.max_cycles = 10;
  options.grid_origin_ns = clock.now;
  options.clock = &clock;
  std::int64_t deadline = 0, regrid = 0;
  std::vector<std::int64_t> seen;
  const std::int64_t new_origin = clock.now + 3'000'000;  // 3 ms later in the period
  LoopCycle cycle;
  cycle.deadline_ns = &deadline;
  cycle.regrid_ns = &regrid;
  cycle.work = [&] {
    seen.push_back(deadline);
    if (seen.size() == 4) regrid = new_origin;
    return true;
  };
  LoopTiming timing;
  run_periodic(options, timing, cycle);
  ASSERT_EQ(seen.size(), 10u);
  EXPECT_EQ(seen, clock.deadlines);
  for (std::size_t k = 0; k < 4; ++k)
    EXPECT_EQ((seen[k] - options.grid_origin_ns) % options.period_ns, 0) << k;
  for (std::size_t k = 4; k < seen.size(); ++k) {
    EXPECT_EQ((seen[k] - new_origin) % options.period_ns, 0) << k;
    EXPECT_GT(seen[k], seen[k - 1]) << k;
  }
  EXPECT_EQ(seen[4] - seen[3], 3'000'000) << "the next point of the new grid";
  EXPECT_EQ(regrid, 0) << "taken";
}

TEST(PeriodicLoop, OnTheRealClockItSleepsToItsDeadlines) {
  // The real clock, checked only from below (a loaded machine may always be later):
  // 20 periods of 5 ms never take less than 20 periods from the start.
  LoopOptions options;
  options.period_ns = 5'000'000;
  options.max_cycles = 20;
  LoopTiming timing;
  const std::int64_t start = monotonic_ns();
  std::int64_t last = 0;
  run_periodic(options, timing, [&] {
    last = monotonic_ns();
    return true;
  });
  EXPECT_EQ(timing.cycles(), 20u);
  EXPECT_GE(last - start, 20 * 5'000'000);
}

TEST(PeriodicLoop, TheCycleCanEndTheLoop) {
  LoopOptions options;
  options.period_ns = 1'000'000;
  LoopTiming timing;
  int cycles = 0;
  run_periodic(options, timing, [&] { return ++cycles < 7; });
  EXPECT_EQ(cycles, 7);
}

// A percentile read from the histogram: never below the exact one (nearest rank of
// the same samples), less than 1/128 above it (latency_histogram.hpp).
void expect_near_exact(double read_us, double exact_us) {
  EXPECT_GE(read_us, exact_us);
  EXPECT_LT(read_us, exact_us * (1.0 + 1.0 / 128)) << "exact " << exact_us << " us";
}

TEST(LoopTiming, PercentilesOfKnownDurations) {
  LoopTiming timing;
  // Wake-up latencies 0.5, 1.5, ..., 999.5 us; compute 10 us except ten of 5 ms.
  for (int i = 0; i < 1000; ++i) timing.record(i * 1000 + 500, i % 100 == 99 ? 5'000'000 : 10'000);
  timing.count_overruns(3);
  timing.count_late(2);
  LoopStats stats;
  timing.fill(stats);
  EXPECT_EQ(stats.cycles, 1000u);
  EXPECT_EQ(stats.overruns, 3u);
  EXPECT_EQ(stats.late_commands, 2u);
  expect_near_exact(stats.wake_latency.p50_us, 499.5);  // the 500th of 1000
  expect_near_exact(stats.wake_latency.p99_us, 989.5);
  expect_near_exact(stats.wake_latency.p999_us, 998.5);
  EXPECT_DOUBLE_EQ(stats.wake_latency.max_us, 999.5);
  // 1% of the cycles are slow: p99 still falls among the fast ones, p99.9 does not.
  expect_near_exact(stats.compute.p50_us, 10.0);
  expect_near_exact(stats.compute.p99_us, 10.0);
  EXPECT_DOUBLE_EQ(stats.compute.p999_us, 5000.0);  // capped at the exact maximum
  EXPECT_DOUBLE_EQ(stats.compute.max_us, 5000.0);
}

// What runs after the work (statistics published, events said) is outside the
// compute time but not lost: its time is counted, on the test's clock.
TEST(PeriodicLoop, TheTimeAfterTheWorkIsCounted) {
  FakeClock clock;
  LoopOptions options;
  options.period_ns = 1'000'000;
  options.max_cycles = 10;
  options.clock = &clock;
  LoopTiming timing;
  int cycle = 0;
  run_periodic(
      options, timing, [&] { return true; },
      [&](std::int64_t) { clock.now += ++cycle == 5 ? 400'000 : 20'000; });
  EXPECT_EQ(timing.housekeeping_max_ns(), 400'000);
  EXPECT_EQ(timing.housekeeping_total_ns(), 9 * 20'000 + 400'000);
  EXPECT_EQ(timing.compute().max_us(), 0.0);
}

// Time the work says it spent waiting (a controller following a catching-up physics)
// is not compute time.
TEST(PeriodicLoop, TheWorkTimeSpentWaitingIsNotComputeTime) {
  FakeClock clock;
  LoopOptions options;
  options.period_ns = 1'000'000;
  options.max_cycles = 10;
  options.clock = &clock;
  LoopTiming timing;
  std::int64_t waited = 0;
  LoopCycle cycle;
  cycle.waited_ns = &waited;
  cycle.work = [&] {
    clock.now += 100'000;  // computing
    waited = 600'000;      // then waiting
    clock.now += waited;
    return true;
  };
  run_periodic(options, timing, cycle);
  EXPECT_EQ(timing.cycles(), 10u);
  EXPECT_DOUBLE_EQ(timing.compute().max_us(), 100.0);
  EXPECT_EQ(waited, 0) << "set back for the next cycle";
  EXPECT_EQ(timing.overruns(), 0u);
}

TEST(LoopTiming, EmptyHistogramReadsZero) {
  LoopTiming timing;
  LoopStats stats;
  timing.fill(stats);
  EXPECT_EQ(stats.wake_latency.p50_us, 0.0);
  EXPECT_EQ(stats.compute.max_us, 0.0);
}

// A loop under the normal scheduler would wake up to 50 us late on every cycle with
// the timer slack Linux gives a thread; the loop's thread takes 1 ns, or its default
// with 0. A thread's default is its creator's slack when it was made: 54 321 ns here,
// so that neither value can be there by chance.
TEST(Realtime, TheLoopsThreadTakesTheTimerSlackAsked) {
  std::thread([] {
    ASSERT_EQ(prctl(PR_SET_TIMERSLACK, 54'321ul), 0);
    std::thread([] {
      ASSERT_EQ(prctl(PR_GET_TIMERSLACK), 54'321);
      LoopOptions options;
      apply_realtime(options, "test loop");
      EXPECT_EQ(prctl(PR_GET_TIMERSLACK), 1);
      options.timer_slack_ns = 0;
      apply_realtime(options, "test loop");
      EXPECT_EQ(prctl(PR_GET_TIMERSLACK), 54'321);
    }).join();
  }).join();
}

TEST(Realtime, RefusedRequestsAreReportedAndTheLoopRunsAnyway) {
  LoopOptions options;
  options.cpu = 100000;  // no such CPU: refused
  testing::internal::CaptureStderr();
  const RealtimeGrant grant = apply_realtime(options, "test loop");
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_EQ(grant.cpu, -1);
  EXPECT_NE(said.find("test loop: cannot pin to CPU 100000"), std::string::npos) << said;
}

}  // namespace
}  // namespace afhub
