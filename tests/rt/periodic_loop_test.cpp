// The periodic loop: pacing without drift, overruns skipped or caught up and
// counted, as fast as possible with no period, a wait before the work, and the
// loop statistics read from known histogram contents.
#include "afhub/rt/periodic_loop.hpp"

#include <gtest/gtest.h>

#include <string>
#include <thread>
#include <vector>

#include "afhub/hub/stop_signal.hpp"

namespace afhub {
namespace {

TEST(PeriodicLoop, NPeriodsTakeNTimesThePeriodWithoutDrift) {
  LoopOptions options;
  options.period_ns = 5'000'000;
  options.max_cycles = 200;
  LoopTiming timing;
  int cycles = 0;
  const std::int64_t start = monotonic_ns();
  run_periodic(options, timing, [&] {
    ++cycles;
    return true;
  });
  const std::int64_t elapsed = monotonic_ns() - start;
  EXPECT_EQ(cycles, 200);
  EXPECT_EQ(timing.cycles(), 200u);
  // 200 periods of 5 ms: 1 s, within one period either way, plus any periods a
  // stall of this shared machine made the loop skip (counted as overruns).
  const double periods = 200.0 + static_cast<double>(timing.overruns());
  EXPECT_NEAR(static_cast<double>(elapsed), periods * 5e6, 5e6);
  EXPECT_LT(timing.overruns(), 20u);
}

TEST(PeriodicLoop, WakeUpsStayOnTheGridDespiteSlowCycles) {
  // Every cycle works for 60% of a period: a loop re-based on "now + period"
  // would drift by that much per cycle; absolute deadlines do not.
  LoopOptions options;
  options.period_ns = 5'000'000;
  options.max_cycles = 100;
  LoopTiming timing;
  const std::int64_t start = monotonic_ns();
  run_periodic(options, timing, [&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(3));
    return true;
  });
  const std::int64_t elapsed = monotonic_ns() - start;
  // The last cycle wakes on the grid, at 100 periods plus any skipped by a stall of
  // this shared machine, and works 3 ms more. Re-basing would add 3 ms per cycle.
  const double periods = 100.0 + static_cast<double>(timing.overruns());
  EXPECT_NEAR(static_cast<double>(elapsed), periods * 5e6 + 3e6, 5e6);
  EXPECT_LT(timing.overruns(), 50u);
  EXPECT_GE(timing.compute().percentile_us(0.5), 3000.0);
}

TEST(PeriodicLoop, AnOverrunSkipsTheMissedPeriodsAndCountsThem) {
  LoopOptions options;
  options.period_ns = 10'000'000;
  options.max_cycles = 20;
  LoopTiming timing;
  int cycle = 0;
  const std::int64_t start = monotonic_ns();
  run_periodic(options, timing, [&] {
    // Cycle 5 runs for 2.5 periods: the next two deadlines pass while it works.
    if (++cycle == 5) std::this_thread::sleep_for(std::chrono::milliseconds(25));
    return true;
  });
  const std::int64_t elapsed = monotonic_ns() - start;
  EXPECT_EQ(timing.cycles(), 20u);
  // Two periods skipped (a stall of the machine may add one more).
  EXPECT_GE(timing.overruns(), 2u);
  EXPECT_LE(timing.overruns(), 3u);
  // Skipped, not made up in a burst: 20 cycles span 20 + 2 periods.
  EXPECT_GE(static_cast<double>(elapsed), 22.0 * 1e7 - 1e7);
  EXPECT_LE(static_cast<double>(elapsed), 22.0 * 1e7 + 2e7);
}

TEST(PeriodicLoop, CatchingUpRunsTheLateCyclesBackToBack) {
  LoopOptions options;
  options.period_ns = 10'000'000;
  options.max_cycles = 20;
  options.overrun = OverrunPolicy::kCatchUp;
  LoopTiming timing;
  int cycle = 0;
  const std::int64_t start = monotonic_ns();
  run_periodic(options, timing, [&] {
    // Cycle 5 runs for 2.5 periods: cycles 6 and 7 follow at once to make up for it.
    if (++cycle == 5) std::this_thread::sleep_for(std::chrono::milliseconds(25));
    return true;
  });
  const std::int64_t elapsed = monotonic_ns() - start;
  EXPECT_EQ(timing.cycles(), 20u);
  EXPECT_GE(timing.overruns(), 1u);  // cycle 5, and any the machine's stalls add
  // Made up, not skipped: 20 cycles span 20 periods, as if nothing had been late.
  EXPECT_GE(static_cast<double>(elapsed), 20.0 * 1e7 - 1e7);
  EXPECT_LE(static_cast<double>(elapsed), 20.0 * 1e7 + 2e7);
}

TEST(PeriodicLoop, PeriodZeroRunsAsFastAsPossible) {
  LoopOptions options;
  options.period_ns = 0;
  options.max_cycles = 100'000;
  LoopTiming timing;
  const std::int64_t start = monotonic_ns();
  run_periodic(options, timing, [] { return true; });
  EXPECT_EQ(timing.cycles(), 100'000u);
  EXPECT_EQ(timing.overruns(), 0u);
  // A period of even 1 us would take 100 ms; no sleeping takes far less.
  EXPECT_LT(monotonic_ns() - start, 5'000'000'000);
}

TEST(PeriodicLoop, TheWaitRunsFirstUntimedAndCanEndTheLoop) {
  LoopOptions options;
  options.period_ns = 1'000'000;
  LoopTiming timing;
  std::vector<char> order;
  LoopCycle cycle;
  cycle.wait = [&] {
    order.push_back('w');
    std::this_thread::sleep_for(std::chrono::milliseconds(5));  // not compute time
    return order.size() < 7;
  };
  cycle.work = [&] {
    order.push_back('c');
    return true;
  };
  cycle.after = [&](std::int64_t) { order.push_back('a'); };
  run_periodic(options, timing, cycle);
  EXPECT_EQ(std::string(order.begin(), order.end()), "wcawcaw");
  EXPECT_EQ(timing.cycles(), 2u);
  EXPECT_LT(timing.compute().max_us(), 5000.0);
}

TEST(PeriodicLoop, AGivenGridOriginSetsThePhaseOfEveryWakeUp) {
  // The origin lies 2.3 periods in the past: wake-ups fall on origin + k * period,
  // 0.7 periods from now first, never on now + period.
  LoopOptions options;
  options.period_ns = 10'000'000;
  options.max_cycles = 10;
  options.grid_origin_ns = monotonic_ns() - 23'000'000;
  LoopTiming timing;
  std::vector<std::int64_t> woke;
  run_periodic(options, timing, [&] {
    woke.push_back(monotonic_ns());
    return true;
  });
  ASSERT_EQ(woke.size(), 10u);
  for (std::int64_t at : woke) {
    // The phase on the grid: how late after a grid point, below 2 ms on a loaded machine.
    const std::int64_t phase = (at - options.grid_origin_ns) % options.period_ns;
    EXPECT_LT(phase, 2'000'000) << "woke " << phase << " ns after a grid point";
  }
  // A future origin is the first wake-up.
  options.max_cycles = 1;
  options.grid_origin_ns = monotonic_ns() + 35'000'000;
  woke.clear();
  run_periodic(options, timing, [&] {
    woke.push_back(monotonic_ns());
    return true;
  });
  EXPECT_GE(woke.at(0), options.grid_origin_ns);
  EXPECT_LT(woke.at(0), options.grid_origin_ns + 2'000'000);
}

TEST(PeriodicLoop, TheCycleCanEndTheLoop) {
  LoopOptions options;
  options.period_ns = 1'000'000;
  LoopTiming timing;
  int cycles = 0;
  run_periodic(options, timing, [&] { return ++cycles < 7; });
  EXPECT_EQ(cycles, 7);
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
  // Percentiles read as the upper edge of their 1 us bin.
  EXPECT_DOUBLE_EQ(stats.wake_latency.p50_us, 500.0);
  EXPECT_DOUBLE_EQ(stats.wake_latency.p99_us, 990.0);
  EXPECT_DOUBLE_EQ(stats.wake_latency.p999_us, 999.0);
  EXPECT_DOUBLE_EQ(stats.wake_latency.max_us, 999.5);
  // 1% of the cycles are slow: p99 still falls among the fast ones, p99.9 does not.
  EXPECT_DOUBLE_EQ(stats.compute.p50_us, 11.0);
  EXPECT_DOUBLE_EQ(stats.compute.p99_us, 11.0);
  EXPECT_DOUBLE_EQ(stats.compute.p999_us, 5000.0);
  EXPECT_DOUBLE_EQ(stats.compute.max_us, 5000.0);
}

TEST(LoopTiming, EmptyHistogramReadsZero) {
  LoopTiming timing;
  LoopStats stats;
  timing.fill(stats);
  EXPECT_EQ(stats.wake_latency.p50_us, 0.0);
  EXPECT_EQ(stats.compute.max_us, 0.0);
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
