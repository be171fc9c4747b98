// The body's states are stale when their stamp is old or when no new one came for the
// stale time, whichever is first; a new physics (its sequence from 1) is fresh at once.
#include "afhub/teleop/state_freshness.hpp"

#include <gtest/gtest.h>

namespace afhub::teleop {
namespace {

constexpr std::int64_t kOneMs = 1'000'000;

TEST(StateFreshness, APhysicsThatStopsIsStaleOnceItsNewestStateIsOlderThanTheBound) {
  StateFreshness freshness(50 * kOneMs);
  std::int64_t now = 1000 * kOneMs;
  std::uint64_t sequence = 1;
  for (; sequence < 100; ++sequence, now += kOneMs)
    EXPECT_FALSE(freshness.stale(sequence, now, now));  // a state each cycle
  const std::int64_t last = now - kOneMs;
  --sequence;
  EXPECT_FALSE(freshness.stale(sequence, last, last + 50 * kOneMs));
  EXPECT_TRUE(freshness.stale(sequence, last, last + 51 * kOneMs));
  // A state published late but seen now is judged by its stamp.
  EXPECT_TRUE(freshness.stale(sequence + 1, last + kOneMs, last + 60 * kOneMs));
  // A restarted physics: sequence from 1 again, fresh at once.
  EXPECT_FALSE(freshness.stale(1, last + 61 * kOneMs, last + 61 * kOneMs));
}

TEST(StateFreshness, AFrozenStampFromTheFutureGoesStaleByThisLoopsClock) {
  StateFreshness freshness(50 * kOneMs);
  const std::int64_t now = 1000 * kOneMs;
  const std::int64_t future = now + 3'600'000 * kOneMs;  // an hour ahead: a faulty writer
  EXPECT_FALSE(freshness.stale(7, future, now));
  EXPECT_FALSE(freshness.stale(7, future, now + 50 * kOneMs));
  EXPECT_TRUE(freshness.stale(7, future, now + 51 * kOneMs));
}

TEST(StateFreshness, ALoopThatWasDescheduledJudgesOnReturnNotAfterMoreCycles) {
  StateFreshness freshness(50 * kOneMs);
  const std::int64_t now = 1000 * kOneMs;
  EXPECT_FALSE(freshness.stale(5, now, now));
  // The loop did not run for 80 ms and the physics published nothing meanwhile.
  EXPECT_TRUE(freshness.stale(5, now, now + 80 * kOneMs));
}

}  // namespace
}  // namespace afhub::teleop
