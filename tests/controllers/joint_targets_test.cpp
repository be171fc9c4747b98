// The shipped joint controllers: sine, hold and track targets, and trajectory files.
#include "afhub/controllers/joint_targets.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "afhub/shm_layout/error.hpp"
#include "model_files.hpp"

namespace afhub {
namespace {

BodyState state_at(double time_s, std::initializer_list<double> positions) {
  BodyState state;
  state.header.sim_time_s = time_s;
  state.joint_count = static_cast<std::uint32_t>(positions.size());
  std::size_t j = 0;
  for (double position : positions) state.joints[j++].position = position;
  return state;
}

TEST(JointControllers, SineStartsAtTheInitialPositionsAndSpreadsThePhases) {
  ControllerCycle cycle = joint_position_controller(sine_targets(0.2, 2.0, {}));
  BodyCommand command;
  cycle(state_at(10.0, {0.5, -0.5, 1.0, 0.0}), command);
  ASSERT_EQ(command.joint_count, 4u);
  for (int j = 0; j < 4; ++j) {
    EXPECT_EQ(command.joints[j].type, JointCommandType::kPosition);
    EXPECT_DOUBLE_EQ(command.joints[j].value, (std::array{0.5, -0.5, 1.0, 0.0})[j]);
  }
  // After the ramp (one period), at t = 2.25 s: 0.2 sin(2 pi 2.25 / 2 + 2 pi j / 4),
  // around the first state's positions whatever the joints read now.
  cycle(state_at(12.25, {9.0, 9.0, 9.0, 9.0}), command);
  for (int j = 0; j < 4; ++j) {
    const double expected =
        (std::array{0.5, -0.5, 1.0, 0.0})[j] +
        0.2 * std::sin(2 * std::numbers::pi * 2.25 / 2.0 + std::numbers::pi * j / 2);
    EXPECT_NEAR(command.joints[j].value, expected, 1e-12) << "joint " << j;
  }
}

TEST(JointControllers, SineMovesOnlyTheChosenJoints) {
  ControllerCycle cycle = joint_position_controller(sine_targets(0.3, 1.0, {2}));
  BodyCommand command;
  cycle(state_at(0.0, {0.1, 0.2, 0.3}), command);
  cycle(state_at(1.25, {0, 0, 0}), command);
  EXPECT_DOUBLE_EQ(command.joints[0].value, 0.1);
  EXPECT_DOUBLE_EQ(command.joints[1].value, 0.2);
  EXPECT_NEAR(command.joints[2].value, 0.3 + 0.3, 1e-12);  // a quarter period after the ramp
}

TEST(JointControllers, HoldKeepsTheFirstPositions) {
  ControllerCycle cycle = joint_position_controller(hold_targets());
  BodyCommand command;
  cycle(state_at(0.0, {0.1, -0.2}), command);
  cycle(state_at(5.0, {1.0, 1.0}), command);
  EXPECT_EQ(command.joint_count, 2u);
  EXPECT_DOUBLE_EQ(command.joints[0].value, 0.1);
  EXPECT_DOUBLE_EQ(command.joints[1].value, -0.2);
}

TEST(JointControllers, TrackInterpolatesAndHoldsTheEnds) {
  testing::ModelFolder folder;
  const std::string file =
      folder.write("path.csv", "time,q0,q1\n0,0,1\n1,1,1\n# a comment\n3,1,-1\n");
  ControllerCycle cycle = joint_position_controller(track_targets(read_trajectory_csv(file)));
  BodyCommand command;
  const auto at = [&](double t) {
    cycle(state_at(100.0 + t, {5, 5, 5}), command);
    return std::array{command.joints[0].value, command.joints[1].value, command.joints[2].value};
  };
  EXPECT_EQ(at(0.0), (std::array{0.0, 1.0, 5.0}));  // the third joint is not in the file: holds
  EXPECT_EQ(at(0.25), (std::array{0.25, 1.0, 5.0}));
  EXPECT_EQ(at(2.0), (std::array{1.0, 0.0, 5.0}));
  EXPECT_EQ(at(10.0), (std::array{1.0, -1.0, 5.0}));
}

TEST(JointControllers, BadTrajectoryFilesSayWhereAndWhat) {
  testing::ModelFolder folder;
  const struct {
    const char* text;
    const char* expected;
  } cases[] = {
      {"0,1\n1,x\n", "path.csv:2: error: column 2 is 'x', not a finite decimal number"},
      {"0,1\n1,0x10\n", "path.csv:2: error: column 2 is '0x10', not a finite decimal number"},
      {"0,1\n0,2\n", "path.csv:2: error: time 0 does not increase"},
      {"0,1,2\n1,2\n", "path.csv:2: error: this row has 1 joint positions, the first had 2"},
      {"0\n", "path.csv:1: error: a row needs a time and at least one joint position"},
      {"t,q\n", "path.csv: error: no trajectory rows"},
      {"0,1\n1,nan\n", "path.csv:2: error: column 2 is 'nan', not a finite decimal number"},
  };
  for (const auto& c : cases) {
    const std::string file = folder.write("path.csv", c.text);
    try {
      read_trajectory_csv(file);
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(c.expected), std::string::npos)
          << error.what() << "\nexpected: " << c.expected;
    }
  }
  EXPECT_THROW(read_trajectory_csv(folder.dir().string() + "/missing.csv"), Error);
}

}  // namespace
}  // namespace afhub

namespace afhub {
namespace {

BodyState state_of(std::uint32_t pid, std::uint64_t step, std::initializer_list<double> positions) {
  BodyState state = state_at(static_cast<double>(step) * 0.001, positions);
  state.header.sim_step = step;
  state.header.publisher_pid = pid;
  return state;
}

// A `ctl sine` that outlived its physics: its trajectory had run 181 s; the new
// physics starts at 0. Restarted from where the joints are, ramping in again, the
// targets stay near the joints instead of t = -181 s driving them to their limits.
TEST(JointControllers, WhenSimulatedTimeJumpsBackTheTrajectoryRestartsFromTheJoints) {
  for (const bool restart : {true, false}) {  // a new physics, or `afhub world reset`
    ControllerCycle cycle = joint_position_controller(sine_targets(0.3, 2.0, {}));
    BodyCommand command;
    cycle(state_of(100, 1000, {0.0, 0.0}), command);
    cycle(state_of(100, 182'000, {0.1, -0.2}), command);  // 181 s later
    const std::uint32_t pid = restart ? 200 : 100;
    cycle(state_of(pid, 1, {0.7, -0.4}), command);
    ASSERT_EQ(command.joint_count, 2u);
    // Time 0 of the new trajectory: the joints' own positions.
    EXPECT_DOUBLE_EQ(command.joints[0].value, 0.7) << "restart " << restart;
    EXPECT_DOUBLE_EQ(command.joints[1].value, -0.4) << "restart " << restart;
    // 10 ms in, still ramping: within the amplitude of where the joints were.
    cycle(state_of(pid, 11, {0.7, -0.4}), command);
    EXPECT_NEAR(command.joints[0].value, 0.7, 0.3 * 0.01 / 2.0 + 1e-12);
    EXPECT_NEAR(command.joints[1].value, -0.4, 0.3 * 0.01 / 2.0 + 1e-12);
  }
}

}  // namespace
}  // namespace afhub
