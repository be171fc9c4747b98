// A free-running controller's phase (controllers/controller.hpp): its grid point is a
// fixed time after the physics' step was due, from the due time the state carries, or
// from the publish stamp when the physics is not paced by the clock.
#include <gtest/gtest.h>

#include "afhub/controllers/controller.hpp"

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

}  // namespace
}  // namespace afhub
