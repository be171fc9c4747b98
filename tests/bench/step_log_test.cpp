// The physics' step log as the benches read it, and its late commands told apart by
// whether the physics ran behind its grid: from written logs and known steps.
#include "afhub/bench/step_log.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <vector>

#include "afhub/shm_layout/error.hpp"

namespace afhub::bench {
namespace {

constexpr std::int64_t kMs = 1'000'000;

// A step due at `due_ms` that woke `woke_late_us` after it, read its commands in 10 us
// and ran 40 us, with `late` commands late.
LoggedStep step(std::int64_t due_ms, std::int64_t woke_late_us, std::uint32_t late) {
  const std::int64_t due = due_ms * kMs;
  return {due + woke_late_us * 1000 + 10'000, due, {10.0F, 35.0F, 5.0F}, late};
}

TEST(LateCommands, OnTimeStepsGiveTheirLateCommandsToNoStall) {
  const std::vector<LoggedStep> steps{step(1, 40, 0), step(2, 50, 1), step(3, 45, 2)};
  const LateCommands counted = late_commands(steps);
  EXPECT_EQ(counted.late, 3U);
  EXPECT_EQ(counted.behind, 0U);
  EXPECT_EQ(counted.falls, 0U);
  EXPECT_EQ(counted.woke_late, 0U);
  EXPECT_EQ(counted.on_grid_steps, 3U);
}

// A 3 ms stall: the physics wakes 2.4 ms late for step 2 and catches up back to back;
// the step after the last one behind is still the stall's, the one after that is not.
TEST(LateCommands, AStallAndItsCatchUpAreTheMachines) {
  std::vector<LoggedStep> steps{step(1, 40, 0), step(2, 2400, 0)};
  // Catch-up: each begins as the one before ends, 1 ms less behind each time.
  for (std::int64_t due_ms = 3; due_ms <= 4; ++due_ms) {
    const LoggedStep& before = steps.back();
    const std::int64_t woke = before.begin_ns + 40'000;
    steps.push_back({woke + 10'000, due_ms * kMs, {10.0F, 35.0F, 5.0F}, 1});
  }
  steps.push_back(step(5, 40, 1));  // after the last step behind (step 4, 0.5 ms behind)
  steps.push_back(step(6, 40, 1));  // on time after one on time: not the stall's
  const LateCommands counted = late_commands(steps);
  EXPECT_EQ(counted.late, 4U);
  EXPECT_EQ(counted.behind, 3U);
  EXPECT_EQ(counted.falls, 1U);
  EXPECT_EQ(counted.woke_late, 1U);
  EXPECT_EQ(counted.on_grid_steps, 2U);  // 1 and 6
}

// A physics whose steps take longer than its period falls behind by itself: not a
// late wake-up.
TEST(LateCommands, APhysicsOverItsPeriodFallsBehindByItself) {
  std::vector<LoggedStep> steps{step(1, 40, 0)};
  for (std::int64_t due_ms = 2; due_ms <= 6; ++due_ms) {
    const LoggedStep& before = steps.back();
    const std::int64_t end = before.begin_ns + 1'200'000;  // 1.2 ms of physics
    steps.push_back(
        {std::max(end, due_ms * kMs) + 10'000, due_ms * kMs, {10.0F, 1190.0F, 10.0F}, 2});
  }
  const LateCommands counted = late_commands(steps);
  EXPECT_EQ(counted.falls, 1U);
  EXPECT_EQ(counted.woke_late, 0U);
  EXPECT_GT(counted.behind, 0U);
  EXPECT_EQ(counted.late, 10U);
}

TEST(StepLog, ReadsTheStepsInTheWindow) {
  char path[] = "/tmp/afhub_step_log_XXXXXX";
  const int fd = mkstemp(path);
  ASSERT_GE(fd, 0);
  close(fd);
  std::ofstream(path) << "begin_ns step_us commands_us publish_us due_ns late\n"
                      << "1000050 40 10 5 1000000 0\n"
                      << "2000060 42.5 11 6 2000000 3\n"
                      << "3000070 41 12 7 3000000 1\n";
  const std::vector<LoggedStep> steps = read_step_log(path, 2'000'000, 2'500'000);
  ASSERT_EQ(steps.size(), 1U);
  EXPECT_EQ(steps[0].begin_ns, 2'000'060);
  EXPECT_EQ(steps[0].due_ns, 2'000'000);
  EXPECT_FLOAT_EQ(steps[0].phases.commands, 11.0F);
  EXPECT_FLOAT_EQ(steps[0].phases.physics, 36.5F);
  EXPECT_FLOAT_EQ(steps[0].phases.publish, 6.0F);
  EXPECT_EQ(steps[0].late, 3U);
  // The format before `due_ns late` (or anything else) is refused, saying the file.
  std::ofstream(path) << "begin_ns step_us commands_us publish_us\n1000050 40 10 5\n";
  try {
    read_step_log(path, 0, 10'000'000);
    ADD_FAILURE() << "an old step log was read";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find(path), std::string::npos) << error.what();
  }
  std::remove(path);
}

}  // namespace
}  // namespace afhub::bench
