// The body's physics is silent when its newest state's stamp is old or when no new one
// came for the stale time, whichever is first; not stepping when states come but their
// step stays; starting until a step is seen, from the first state and after a silence (a
// new physics, its sequence from 1, is live at its first step); restarted, off for a
// while, when its sequence or step goes back with no silence between.
#include "afhub/teleop/state_freshness.hpp"

#include <gtest/gtest.h>

namespace afhub::teleop {
namespace {

constexpr std::int64_t kOneMs = 1'000'000;
constexpr auto kLive = PhysicsLiveness::kLive;
constexpr auto kSilent = PhysicsLiveness::kSilent;
constexpr auto kNotStepping = PhysicsLiveness::kNotStepping;
constexpr auto kStarting = PhysicsLiveness::kStarting;

TEST(StateFreshness, APhysicsThatStopsIsSilentOnceItsNewestStateIsOlderThanTheBound) {
  StateFreshness freshness(50 * kOneMs);
  std::int64_t now = 1000 * kOneMs;
  std::uint64_t sequence = 1;
  EXPECT_EQ(freshness.judge(sequence, now, sequence, now), kStarting);
  for (++sequence, now += kOneMs; sequence < 100; ++sequence, now += kOneMs)
    EXPECT_EQ(freshness.judge(sequence, now, sequence, now), kLive);  // a step each cycle
  const std::int64_t last = now - kOneMs;
  --sequence;
  EXPECT_EQ(freshness.judge(sequence, last, sequence, last + 50 * kOneMs), kLive);
  EXPECT_EQ(freshness.judge(sequence, last, sequence, last + 51 * kOneMs), kSilent);
  // A state published late but seen now is judged by its stamp.
  EXPECT_EQ(freshness.judge(sequence + 1, last + kOneMs, sequence + 1, last + 60 * kOneMs),
            kSilent);
  // A restarted physics: sequence and step from 1 again, live at its first step.
  EXPECT_EQ(freshness.judge(1, last + 61 * kOneMs, 1, last + 61 * kOneMs), kStarting);
  EXPECT_EQ(freshness.judge(2, last + 62 * kOneMs, 2, last + 62 * kOneMs), kLive);
}

TEST(StateFreshness, AFrozenStampFromTheFutureGoesSilentByThisLoopsClock) {
  StateFreshness freshness(50 * kOneMs);
  const std::int64_t now = 1000 * kOneMs;
  const std::int64_t future = now + 3'600'000 * kOneMs;  // an hour ahead: a faulty writer
  EXPECT_EQ(freshness.judge(6, future, 6, now - kOneMs), kStarting);
  EXPECT_EQ(freshness.judge(7, future, 7, now), kLive);
  EXPECT_EQ(freshness.judge(7, future, 7, now + 50 * kOneMs), kLive);
  EXPECT_EQ(freshness.judge(7, future, 7, now + 51 * kOneMs), kSilent);
}

TEST(StateFreshness, ALoopThatWasDescheduledJudgesOnReturnNotAfterMoreCycles) {
  StateFreshness freshness(50 * kOneMs);
  const std::int64_t now = 1000 * kOneMs;
  EXPECT_EQ(freshness.judge(4, now - kOneMs, 4, now - kOneMs), kStarting);
  EXPECT_EQ(freshness.judge(5, now, 5, now), kLive);
  // The loop did not run for 80 ms and the physics published nothing meanwhile.
  EXPECT_EQ(freshness.judge(5, now, 5, now + 80 * kOneMs), kSilent);
}

TEST(StateFreshness, StatesThatComeWithoutANewStepAreNotSteppingUntilOneSteps) {
  StateFreshness freshness(50 * kOneMs);
  std::int64_t now = 1000 * kOneMs;
  const std::uint64_t step = 300;
  // Paused at step 300: a new state every millisecond, the same step.
  std::uint64_t sequence = 1;
  EXPECT_EQ(freshness.judge(sequence++, now, step - 1, now), kStarting);
  now += kOneMs;
  for (int ms = 0; ms <= 50; ++ms, ++sequence, now += kOneMs)
    EXPECT_EQ(freshness.judge(sequence, now, step, now), kLive) << ms;
  EXPECT_EQ(freshness.judge(sequence, now, step, now), kNotStepping);
  // Fresh states do not make it live; silence wins over not stepping.
  EXPECT_EQ(freshness.judge(sequence + 1, now + kOneMs, step, now + kOneMs), kNotStepping);
  EXPECT_EQ(freshness.judge(sequence + 1, now + kOneMs, step, now + 60 * kOneMs), kSilent);
  // States again after the silence, then one step (`afhub world step`, a resume): live.
  now += 61 * kOneMs;
  EXPECT_EQ(freshness.judge(sequence + 2, now, step, now), kStarting);
  EXPECT_EQ(freshness.judge(sequence + 3, now + kOneMs, step + 1, now + kOneMs), kLive);
}

// A teleop started against a paused world pushed for its first 50 ms: the world's first
// states looked live until their step had stayed for the stale time.
TEST(StateFreshness, AWorldPausedWhenFirstSeenIsNeverLive) {
  StateFreshness freshness(50 * kOneMs);
  std::int64_t now = 1000 * kOneMs;
  std::uint64_t sequence = 1;
  for (int ms = 0; ms <= 50; ++ms, ++sequence, now += kOneMs)
    EXPECT_EQ(freshness.judge(sequence, now, 300, now), kStarting) << ms;
  EXPECT_EQ(freshness.judge(sequence, now, 300, now), kNotStepping);
  EXPECT_EQ(freshness.judge(sequence + 1, now + kOneMs, 301, now + kOneMs), kLive);
}

// A paused world stepped by hand (`afhub world step 1`): each step moved the body, looked
// live until it had stayed for the stale time, and the force ramped in for those 50 ms.
// Its world state's paused flag keeps the force off; silence still wins.
TEST(StateFreshness, APausedWorldSteppedByHandIsPausedUntilItRunsAndSteps) {
  StateFreshness freshness(50 * kOneMs);
  std::int64_t now = 1000 * kOneMs;
  std::uint64_t sequence = 1, step = 100;
  EXPECT_EQ(freshness.judge(sequence++, now, step++, now), kStarting);
  now += kOneMs;
  EXPECT_EQ(freshness.judge(sequence++, now, step++, now), kLive);
  for (int ms = 0; ms < 200; ++ms, now += kOneMs) {
    if (ms % 20 == 0) ++step;  // a step by hand every 20 ms
    EXPECT_EQ(freshness.judge(sequence++, now, step, now, true), PhysicsLiveness::kPaused) << ms;
  }
  EXPECT_EQ(freshness.judge(sequence, now, step, now + 51 * kOneMs, true), kSilent);
  now += 52 * kOneMs;
  // Resumed: states, then a step.
  EXPECT_EQ(freshness.judge(sequence++, now, step, now), kStarting);
  now += kOneMs;
  EXPECT_EQ(freshness.judge(sequence++, now, step + 1, now), kLive);
}

// A world reset while paused (its step back to 0) is said once it runs again: no force
// until it steps.
TEST(StateFreshness, AResetWhilePausedIsARestartOnceResumed) {
  StateFreshness freshness(50 * kOneMs);
  std::int64_t now = 1000 * kOneMs;
  std::uint64_t sequence = 1;
  EXPECT_EQ(freshness.judge(sequence++, now, 500, now), kStarting);
  now += kOneMs;
  EXPECT_EQ(freshness.judge(sequence++, now, 501, now), kLive);
  for (int ms = 0; ms < 100; ++ms, now += kOneMs)
    EXPECT_EQ(freshness.judge(sequence++, now, ms < 50 ? 501 : 0, now, true),
              PhysicsLiveness::kPaused)
        << ms;
  EXPECT_EQ(freshness.judge(sequence++, now, 0, now), PhysicsLiveness::kRestarted);
  now += kOneMs;
  EXPECT_EQ(freshness.judge(sequence++, now, 1, now), kLive);
}

// A physics restarted within the stale time (its sequence from 1 again) or a world reset
// (its step from 0 again) put the body back at its initial pose while the states never
// stopped: the device got the full force of the new pose error at once, with no ramp.
TEST(StateFreshness, StatesThatGoBackWithoutASilenceTakeTheForceOffBeforeItStepsAgain) {
  for (const bool reset : {false, true}) {
    SCOPED_TRACE(reset ? "world reset" : "physics restarted");
    StateFreshness freshness(50 * kOneMs);
    std::int64_t now = 1000 * kOneMs;
    std::uint64_t sequence = 1;
    std::uint64_t step = 1;
    EXPECT_EQ(freshness.judge(sequence++, now, step++, now), kStarting);
    for (int ms = 0; ms < 100; ++ms) {
      now += kOneMs;
      EXPECT_EQ(freshness.judge(sequence++, now, step++, now), kLive);
    }
    if (!reset) sequence = 1;
    step = 0;
    // Stepping every millisecond from the start: off for kRestartOffNs, then live.
    const std::int64_t back = now + kOneMs;
    for (now = back; now - back < kRestartOffNs; now += kOneMs)
      EXPECT_EQ(freshness.judge(sequence++, now, step++, now), PhysicsLiveness::kRestarted)
          << (now - back) / kOneMs << " ms after";
    EXPECT_EQ(freshness.judge(sequence++, now, step++, now), kLive);
  }
}

// Back, then no step (reset while paused): off until it steps, however long that takes.
TEST(StateFreshness, AWorldResetWhilePausedStaysOffUntilItSteps) {
  StateFreshness freshness(50 * kOneMs);
  std::int64_t now = 1000 * kOneMs;
  EXPECT_EQ(freshness.judge(1, now, 500, now), kStarting);
  EXPECT_EQ(freshness.judge(2, now + kOneMs, 501, now + kOneMs), kLive);
  now += 2 * kOneMs;
  std::uint64_t sequence = 3;
  for (int ms = 0; ms <= 50; ++ms, now += kOneMs)
    EXPECT_EQ(freshness.judge(sequence++, now, 0, now), PhysicsLiveness::kRestarted) << ms;
  EXPECT_EQ(freshness.judge(sequence++, now, 0, now), kNotStepping);
  EXPECT_EQ(freshness.judge(sequence++, now + kOneMs, 1, now + kOneMs), kLive);
}

}  // namespace
}  // namespace afhub::teleop
