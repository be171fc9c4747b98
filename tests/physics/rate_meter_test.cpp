// The physics loop's achieved rate after a pause and a reset, on made-up times.
#include "afhub/physics/rate_meter.hpp"

#include <gtest/gtest.h>

namespace afhub::physics {
namespace {

constexpr std::int64_t kMs = 1'000'000;

// Runs `count` cycles of 1 ms from `now`, a step each when running.
void cycles(RateMeter& meter, std::int64_t& now, std::uint64_t& steps, int count, bool running) {
  for (int i = 0; i < count; ++i) {
    now += kMs;
    if (running) ++steps;
    meter.update(now, steps, running);
  }
}

TEST(RateMeter, PausedTimeIsInNoWindow) {
  RateMeter meter;
  std::int64_t now = 0;
  std::uint64_t steps = 0;
  cycles(meter, now, steps, 1500, true);
  EXPECT_NEAR(meter.rate_hz(), 1000.0, 1.0);
  cycles(meter, now, steps, 830, false);  // paused 0.83 s
  EXPECT_EQ(meter.rate_hz(), 0.0);
  cycles(meter, now, steps, 1200, true);  // resumed: a window of running only
  EXPECT_NEAR(meter.rate_hz(), 1000.0, 1.0) << "a second mostly paused read 168 Hz";
}

TEST(RateMeter, AResetStartsAWindowAgain) {
  RateMeter meter;
  std::int64_t now = 0;
  std::uint64_t steps = 0;
  cycles(meter, now, steps, 700, true);
  meter.restart();
  now += 400 * kMs;  // the reset took long: no steps in that time
  meter.update(now, steps, true);
  cycles(meter, now, steps, 1001, true);
  EXPECT_NEAR(meter.rate_hz(), 1000.0, 1.0);
}

}  // namespace
}  // namespace afhub::physics
