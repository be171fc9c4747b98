// The rule `afhub world`, Python's World and the viewer share to see a world command
// done (hub/client's world_action_watch.hpp): fed world states by hand.
#include "afhub/hub/world_action_watch.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <string>

namespace afhub {
namespace {

constexpr std::int64_t kSentNs = 1'000'000'000;

// A world state at `step` (1 ms a step), published `after_send_ns` after the command.
WorldState at_step(std::uint64_t step, bool paused, std::int64_t after_send_ns = 1) {
  WorldState state;
  state.header.sim_step = step;
  state.header.sim_time_s = static_cast<double>(step) * 1e-3;
  state.header.publish_stamp_ns = kSentNs + after_send_ns;
  state.paused = paused ? 1 : 0;
  return state;
}

TEST(WorldActionWatch, PauseAndResumeAreShownByThePausedFlag) {
  WorldActionWatch pause(WorldAction::kPause, 1, at_step(10, false, -5), kSentNs);
  EXPECT_EQ(pause.shown(at_step(11, false)), std::nullopt);
  EXPECT_EQ(pause.shown(at_step(12, true)), "paused at step 12 (t = 0.012 s)");

  WorldActionWatch again(WorldAction::kPause, 1, at_step(12, true, -5), kSentNs);
  EXPECT_EQ(again.shown(at_step(12, true)), "already paused at step 12 (t = 0.012 s)");

  WorldActionWatch resume(WorldAction::kResume, 1, at_step(12, true, -5), kSentNs);
  EXPECT_EQ(resume.shown(at_step(12, true)), std::nullopt);
  EXPECT_EQ(resume.shown(at_step(13, false)), "resumed at step 13 (t = 0.013 s)");
}

TEST(WorldActionWatch, StepsAreShownOnceTheCountHasGoneOnByAll) {
  WorldActionWatch step(WorldAction::kStep, 3, at_step(10, true, -5), kSentNs);
  EXPECT_EQ(step.shown(at_step(11, true)), std::nullopt);
  EXPECT_EQ(step.shown(at_step(12, true)), std::nullopt);
  EXPECT_EQ(step.shown(at_step(13, true)), "stepped 3 steps: now paused at step 13 (t = 0.013 s)");

  WorldActionWatch one(WorldAction::kStep, 1, at_step(10, true, -5), kSentNs);
  EXPECT_EQ(one.shown(at_step(11, true)), "stepped 1 step: now paused at step 11 (t = 0.011 s)");
}

// Steps asked while others run by hand are added to them: the world is still under its
// pause, not halted, once these have gone by (it said "now paused").
TEST(WorldActionWatch, StepsAddedToOthersRunningSaySoOnceTheirCountHasGoneBy) {
  WorldState stepping = at_step(10, false, -5);
  stepping.paused_by_pid = 42;
  WorldActionWatch step(WorldAction::kStep, 5, stepping, kSentNs);
  stepping = at_step(14, false);
  stepping.paused_by_pid = 42;
  EXPECT_EQ(step.shown(stepping), std::nullopt);
  stepping.header.sim_step = 15;
  stepping.header.sim_time_s = 0.015;
  EXPECT_EQ(step.shown(stepping),
            "stepped 5 steps, and steps asked by another run on: now at step 15 (t = 0.015 s)");

  WorldActionWatch resumed(WorldAction::kStep, 2, at_step(10, true, -5), kSentNs);
  EXPECT_EQ(resumed.shown(at_step(12, false)),
            "stepped 2 steps, and the world was resumed since: now running at step 12 (t = "
            "0.012 s)");
}

TEST(WorldActionWatch, ResetIsShownByTheCountGoingBack) {
  WorldActionWatch reset(WorldAction::kReset, 1, at_step(100, false, -5), kSentNs);
  EXPECT_EQ(reset.shown(at_step(101, false)), std::nullopt);
  EXPECT_EQ(reset.shown(at_step(102, false)), std::nullopt);
  EXPECT_EQ(reset.shown(at_step(0, false)), "reset from step 102: now at step 0 (t = 0.000 s)");
}

// From step 0 the count cannot go back: the second state published after sending comes
// from a step that read the command (the first may have read before it came).
TEST(WorldActionWatch, AResetFromStepZeroIsShownByTheSecondStateAfterSending) {
  WorldActionWatch reset(WorldAction::kReset, 1, at_step(0, true, -5), kSentNs);
  EXPECT_EQ(reset.shown(at_step(0, true, -1)), std::nullopt);  // published before sending
  EXPECT_EQ(reset.shown(at_step(0, true)), std::nullopt);
  EXPECT_EQ(reset.shown(at_step(0, true)),
            "reset from step 0: now at step 0 (t = 0.000 s), paused");
}

}  // namespace
}  // namespace afhub
