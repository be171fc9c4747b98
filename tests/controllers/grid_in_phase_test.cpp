// A free-running controller's phase (controllers/controller.hpp): its grid point is a
// fixed time after the physics' step was due, from the due time the state carries, or
// from the publish stamp when the physics is not paced by the clock; and the states
// that move a running loop onto another grid (hub/step_phase.hpp).
#include <gtest/gtest.h>

#include <utility>

#include "afhub/controllers/controller.hpp"
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

}  // namespace
}  // namespace afhub
