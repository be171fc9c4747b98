// A device is stale when the teleoperation loop runs and sees no new sample for the
// stale time; not when the loop itself was descheduled along with the driver.
#include "afhub/teleop/device_freshness.hpp"

#include <gtest/gtest.h>

namespace afhub::teleop {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(DeviceFreshness, ADriverThatStopsWhileTheLoopRunsGoesStaleAfterTheStaleTime) {
  DeviceFreshness freshness(50 * kMs, kMs);
  std::int64_t now = 1000 * kMs;
  EXPECT_FALSE(freshness.stale(now, now));  // a sample each cycle: fresh
  const std::int64_t last_sample = now + kMs;
  for (now += kMs; now <= last_sample + 50 * kMs; now += kMs)
    EXPECT_FALSE(freshness.stale(last_sample, now)) << (now - last_sample) / kMs << " ms";
  EXPECT_TRUE(freshness.stale(last_sample, now));  // 51 ms and 51 cycles without one
  EXPECT_FALSE(freshness.stale(now, now + kMs));   // samples again
}

TEST(DeviceFreshness, ALoopDescheduledWithItsDriverFindsNoStaleDevice) {
  DeviceFreshness freshness(50 * kMs, kMs);
  std::int64_t now = 1000 * kMs;
  EXPECT_FALSE(freshness.stale(now, now));
  const std::int64_t last_sample = now;
  // Neither ran for 200 ms; then the loop runs a few cycles before the driver does.
  now += 200 * kMs;
  for (int cycle = 0; cycle < 10; ++cycle, now += kMs)
    EXPECT_FALSE(freshness.stale(last_sample, now)) << "cycle " << cycle;
  EXPECT_FALSE(freshness.stale(now, now));  // the driver's next sample
  // A driver that does not come back is stale after 50 of the loop's cycles.
  int cycles = 0;
  for (const std::int64_t sample = now; !freshness.stale(sample, now); now += kMs) ++cycles;
  EXPECT_EQ(cycles, 51);
}

// The loop's own standstill: past the stale time and two of its periods.
TEST(StoodStill, PastTheStaleTimeAndTwoPeriods) {
  EXPECT_FALSE(stood_still(kMs, 50 * kMs, kMs));       // a cycle
  EXPECT_FALSE(stood_still(17 * kMs, 50 * kMs, kMs));  // woken late on a loaded machine
  EXPECT_FALSE(stood_still(50 * kMs, 50 * kMs, kMs));  // at the stale time
  EXPECT_TRUE(stood_still(51 * kMs, 50 * kMs, kMs));   // past it
  // A loop slower than the stale time (--rate 10: 100 ms), on time or a cycle late.
  EXPECT_FALSE(stood_still(100 * kMs, 50 * kMs, 100 * kMs));
  EXPECT_FALSE(stood_still(200 * kMs, 50 * kMs, 100 * kMs));
  EXPECT_TRUE(stood_still(201 * kMs, 50 * kMs, 100 * kMs));
}

}  // namespace
}  // namespace afhub::teleop
