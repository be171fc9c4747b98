// A free-running controller's phase (controllers/controller.hpp): its grid point is a
// fixed time after the physics' step was due, from the due time the state carries, or
// from the publish stamp when the physics is not paced by the clock; the states that
// move a running loop onto another grid; and a physics behind its grid followed state
// by state (hub/step_phase.hpp); the late commands a loop takes from the physics' counts
// (hub/physics_late_commands.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <utility>

#include "afhub/controllers/controller.hpp"
#include "afhub/hub/physics_late_commands.hpp"
#include "afhub/hub/step_phase.hpp"

namespace afhub {
namespace {

TEST(GridInPhase, TheGridFollowsTheStepsDueTimeThenThePublishStamp) {
  BodyState state;
  state.step_due_ns = 5'000'000'000;
  state.header.publish_stamp_ns = 5'000'040'000;  // 40 us late: the physics' jitter
  EXPECT_EQ(grid_in_phase(state, 500'000), 5'000'500'000) << "the due time, not the stamp";
  EXPECT_EQ(grid_in_phase(state, 0), 5'000'000'000);
  state.step_due_ns = 0;  // --fast, or a DDS mirror
  EXPECT_EQ(grid_in_phase(state, 500'000), 5'000'540'000);
  EXPECT_EQ(grid_in_phase(state, ControllerOptions::kUnaligned), 0) << "unaligned";
}

// A loop's grid as StepPhase sets it, before and while it runs.
struct PhasedLoop {
  static constexpr std::int64_t kAfter = 500'000, kPeriod = 1'000'000;
  BodyState state;
  StepPhase phase{kAfter, [this] { return &state; }};
  LoopOptions options;
  LoopCycle cycle;

  PhasedLoop(std::uint32_t pid, std::uint64_t step, std::int64_t due, std::int64_t stamp) {
    set(pid, step, due, stamp);
    options.period_ns = kPeriod;
    phase.attach(options, cycle);
  }
  void set(std::uint32_t pid, std::uint64_t step, std::int64_t due, std::int64_t stamp) {
    state.header.publisher_pid = pid;
    state.header.sim_step = step;
    state.step_due_ns = due;
    state.header.publish_stamp_ns = stamp;
  }
  // The grid point the next state asks for (0: none), taken as the loop takes it.
  std::int64_t follow(std::uint32_t pid, std::uint64_t step, std::int64_t due, std::int64_t stamp) {
    set(pid, step, due, stamp);
    phase.follow(state);
    return std::exchange(*cycle.regrid_ns, 0);
  }
};

TEST(StepPhase, ALoopStartedOnTheModelAsLoadedMovesToTheFirstStepsDueTime) {
  // Step 0 (the model as loaded) is published before the physics' clock starts: no
  // due time, so the loop starts from its publish stamp, off the physics' grid.
  PhasedLoop loop(7, 0, 0, 3'000'123'000);
  EXPECT_EQ(loop.options.grid_origin_ns, 3'000'623'000);
  EXPECT_EQ(loop.follow(7, 0, 0, 3'000'123'000), 0) << "the same state again";
  EXPECT_EQ(loop.follow(7, 1, 3'001'400'000, 3'001'420'000), 3'001'900'000)
      << "the first step due: onto the physics' grid";
  EXPECT_EQ(loop.follow(7, 2, 3'002'400'000, 3'002'410'000), 0) << "on it: stays";
  EXPECT_EQ(loop.follow(7, 5, 3'005'400'000, 3'005'460'000), 0) << "steps missed: stays";
}

TEST(StepPhase, APhysicsStartedOverOrAnotherOneMovesTheLoopToItsGrid) {
  PhasedLoop loop(7, 10, 5'000'000'000, 5'000'040'000);
  EXPECT_EQ(loop.options.grid_origin_ns, 5'000'500'000);
  // Re-executed after a hub restart: the same process, counting from step 0 again.
  EXPECT_EQ(loop.follow(7, 0, 0, 6'000'250'000), 6'000'750'000);
  EXPECT_EQ(loop.follow(7, 1, 6'000'300'000, 6'000'320'000), 6'000'800'000);
  EXPECT_EQ(loop.follow(7, 3, 6'002'300'000, 6'002'320'000), 0);
  // Another physics, its first state seen several steps in.
  EXPECT_EQ(loop.follow(9, 40, 7'000'100'000, 7'000'120'000), 7'000'600'000);
  // --fast, or a DDS mirror: no due times, the same grid on.
  PhasedLoop fast(11, 3, 0, 8'000'000'000);
  EXPECT_EQ(fast.follow(11, 4, 0, 8'000'010'000), 0);
}

// The follow is checked on a clock the test drives: a sleep jumps to its deadline.
class SteppedClock final : public LoopClock {
 public:
  std::int64_t now = 10'000'000'000;
  std::int64_t now_ns() noexcept override { return now; }
  void sleep_until_ns(std::int64_t deadline_ns) noexcept override {
    now = std::max(now, deadline_ns);
  }
};

// A loop whose cycle is due at `kCycle` has answered a state; `newer` is what the
// physics publishes next, seen from the reads given by `comes_at_read` on.
struct FollowingLoop {
  static constexpr std::int64_t kPeriod = 1'000'000, kCycle = 10'000'000'000;
  SteppedClock clock;
  BodyState answered, newer;
  std::size_t reads = 0, comes_at_read = ~std::size_t{0};
  StepPhase phase{500'000, [this]() -> const BodyState* {
                    return ++reads >= comes_at_read ? &newer : &answered;
                  }};
  LoopOptions options;
  LoopCycle cycle;

  FollowingLoop(std::int64_t answered_due_ns) {
    answered.header.sim_step = 40;
    answered.step_due_ns = answered_due_ns;
    newer = answered;
    newer.header.sim_step = 41;
    options.period_ns = kPeriod;
    options.clock = &clock;
    phase.attach(options, cycle);
    *cycle.deadline_ns = kCycle;
    clock.now = kCycle + 30'000;  // the loop woke and answered
    reads = 0;
  }
  const BodyState* next() {
    return phase.next_while_catching_up(StepPhase::Answered::of(answered));
  }
  std::int64_t waited() { return std::exchange(*cycle.waited_ns, 0); }
};

TEST(StepPhase, APhysicsOnItsGridIsNotFollowed) {
  // The loop answers half a period after the step was due: the next is not due yet.
  FollowingLoop loop(FollowingLoop::kCycle - 500'000);
  loop.comes_at_read = 1;
  EXPECT_EQ(loop.next(), nullptr);
  EXPECT_EQ(loop.reads, 0u) << "no state read, no wait";
  EXPECT_EQ(loop.waited(), 0);
  // Stopped 0.2 s ago, beyond what a physics catches up: it skips to its grid.
  FollowingLoop stopped(FollowingLoop::kCycle - 200'000'000);
  stopped.comes_at_read = 1;
  EXPECT_EQ(stopped.next(), nullptr);
  EXPECT_EQ(stopped.reads, 0u);
}

TEST(StepPhase, APhysicsBehindItsGridIsFollowedStateByState) {
  // Held 5 ms: its next step was due long ago, so it runs at once.
  FollowingLoop loop(FollowingLoop::kCycle - 5'000'000);
  loop.comes_at_read = 3;  // two 20 us polls find the state answered, the third a new one
  EXPECT_EQ(loop.next(), &loop.newer);
  EXPECT_EQ(loop.reads, 3u);
  EXPECT_EQ(loop.waited(), 40'000) << "the wait, left out of the cycle's compute time";
}

TEST(StepPhase, AFollowEndsBeforeTheLoopsNextCycle) {
  // No new state: the wait ends 20 us before the next cycle, which answers as usual.
  FollowingLoop loop(FollowingLoop::kCycle - 5'000'000);
  EXPECT_EQ(loop.next(), nullptr);
  EXPECT_EQ(loop.clock.now, FollowingLoop::kCycle + FollowingLoop::kPeriod - 20'000);
  EXPECT_EQ(loop.waited(), FollowingLoop::kPeriod - 20'000 - 30'000);
}

TEST(PhysicsLateCommands, TheGrowthOfThePhysicsCountIsTakenAcrossItsWrapAndARestart) {
  PhysicsLateCommands late;
  BodyState state;
  state.header.publisher_pid = 100;
  state.commanded_steps = 50;
  state.answered_steps = 40;
  EXPECT_EQ(late.newly_late(state), 0u) << "the first state: what came before is not ours";
  state.commanded_steps = 60;
  state.answered_steps = 47;
  EXPECT_EQ(late.newly_late(state), 3u);
  // The steps under command wrapped past 2^32: 2 more late.
  state.commanded_steps = 5;
  state.answered_steps = 0xFFFFFFFFu - 9;  // late: 5 - (2^32 - 10) = 15 (mod 2^32)
  EXPECT_EQ(late.newly_late(state), 2u);
  // A restarted physics: its own counts from 0, none of them late for this loop yet.
  state.header.publisher_pid = 200;
  state.commanded_steps = 30;
  state.answered_steps = 10;
  EXPECT_EQ(late.newly_late(state), 0u);
  state.commanded_steps = 31;
  EXPECT_EQ(late.newly_late(state), 1u);
}

}  // namespace
}  // namespace afhub
