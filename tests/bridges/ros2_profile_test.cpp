// --profile ros2 without a network: ROS 2 topic names from channel names, and
// JointState commands checked and turned into BodyCommands (names, the array chosen,
// the joints left unnamed holding, every refusal naming the field).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <memory>

#include "ros2_profile.hpp"

namespace afhub::bridges {
namespace {

TEST(Ros2Topic, ChannelNamesBecomeRosNames) {
  EXPECT_EQ(ros2_topic("", "afhub/arm/base", "joint_states"), "rt/afhub/arm/base/joint_states");
  EXPECT_EQ(ros2_topic("sim", "ambf/env/base", "pose"), "rt/sim/ambf/env/base/pose");
  EXPECT_EQ(ros2_topic("/sim/", "/ambf//env/", "twist"), "rt/sim/ambf/env/twist");
  // ROS names allow [A-Za-z0-9_] and no part starting with a digit.
  EXPECT_EQ(ros2_topic("", "psm-1/tool.tip/2nd", "wrench"), "rt/psm_1/tool_tip/_2nd/wrench");
}

const std::vector<std::string> kJoints{"base-link1", "link1-link2", "link2-link3"};

struct Command {
  std::unique_ptr<BodyCommand, decltype(&std::free)> command{
      static_cast<BodyCommand*>(std::calloc(1, sizeof(BodyCommand))), &std::free};
};

TEST(Ros2JointCommand, NamedJointsTakeTheirValuesTheOthersHold) {
  const char* names[] = {"link2-link3", "base-link1"};
  const double positions[] = {-0.4, 0.6};
  const Ros2JointState in{names, 2, {positions, nullptr, nullptr}, {2, 0, 0}};
  const double hold[] = {0.1, 0.2, 0.3};
  Command out;
  EXPECT_EQ(ros2_joint_command(in, kJoints, hold, out.command.get()), "");
  const BodyCommand& c = *out.command;
  ASSERT_EQ(c.joint_count, 3u);
  EXPECT_EQ(c.joints[0].value, 0.6);
  EXPECT_EQ(c.joints[1].value, 0.2);  // unnamed: holds
  EXPECT_EQ(c.joints[2].value, -0.4);
  for (int j = 0; j < 3; ++j) EXPECT_EQ(c.joints[j].type, JointCommandType::kPosition);
}

TEST(Ros2JointCommand, VelocityOrEffortWhenNoPosition) {
  const char* names[] = {"link1-link2"};
  const double velocities[] = {0.5};
  const double efforts[] = {2.0};
  const double hold[] = {0.1, 0.2, 0.3};
  Command out;
  const Ros2JointState by_velocity{names, 1, {nullptr, velocities, efforts}, {0, 1, 1}};
  EXPECT_EQ(ros2_joint_command(by_velocity, kJoints, hold, out.command.get()), "");
  EXPECT_EQ(out.command->joints[1].type, JointCommandType::kVelocity);
  EXPECT_EQ(out.command->joints[1].value, 0.5);
  EXPECT_EQ(out.command->joints[0].type, JointCommandType::kPosition);
  const Ros2JointState by_effort{names, 1, {nullptr, nullptr, efforts}, {0, 0, 1}};
  EXPECT_EQ(ros2_joint_command(by_effort, kJoints, hold, out.command.get()), "");
  EXPECT_EQ(out.command->joints[1].type, JointCommandType::kEffort);
  EXPECT_EQ(out.command->joints[1].value, 2.0);
}

const double kHold[] = {0.1, 0.2, 0.3};

TEST(Ros2JointCommand, BadCommandsAreRefusedWithTheReason) {
  const double one[] = {0.5};
  const double two[] = {0.5, 0.6};
  const double nan[] = {std::nan("")};
  const char* good[] = {"base-link1"};
  const char* unknown[] = {"elbow"};
  const auto error = [&](const Ros2JointState& in, const double* holding = kHold) {
    return ros2_joint_command(in, kJoints, holding, nullptr);
  };
  EXPECT_NE(error({good, 0, {one, nullptr, nullptr}, {1, 0, 0}}).find("name is empty"),
            std::string::npos);
  EXPECT_NE(error({good, 1, {nullptr, nullptr, nullptr}, {0, 0, 0}}).find("all empty"),
            std::string::npos);
  EXPECT_NE(
      error({good, 1, {two, nullptr, nullptr}, {2, 0, 0}}).find("position has 2 values for 1"),
      std::string::npos);
  EXPECT_NE(error({unknown, 1, {one, nullptr, nullptr}, {1, 0, 0}})
                .find("'elbow' is not a joint of this body (its joints: base-link1, link1-link2"),
            std::string::npos);
  EXPECT_NE(error({good, 1, {nan, nullptr, nullptr}, {1, 0, 0}}).find("position[0] is not finite"),
            std::string::npos);
  // With no state yet, the unnamed joints have nowhere to hold: all must be named.
  EXPECT_NE(error({good, 1, {one, nullptr, nullptr}, {1, 0, 0}}, nullptr).find("no state"),
            std::string::npos);
  const char* all[] = {"base-link1", "link1-link2", "link2-link3"};
  const double three[] = {1, 2, 3};
  EXPECT_EQ(error({all, 3, {three, nullptr, nullptr}, {3, 0, 0}}, nullptr), "");
}

}  // namespace
}  // namespace afhub::bridges
