// The law's output as the body's and the device's commands.
#include "afhub/teleop/teleop_commands.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

namespace afhub::teleop {
namespace {

TeleopOutput grasping_output() {
  TeleopOutput out;
  out.body_wrench = {{1, 2, 3}, {4, 5, 6}};
  out.body_target = {{0.1, 0.2, 0.3}, {0, 0, 1, 0}};
  out.device_wrench = {{-1, 0, 0.5}, {0, 0.1, 0}};
  out.gripper = 0.25;
  out.grasp = true;
  return out;
}

TEST(TeleopCommands, TheBodyGetsTheWrenchTheGripperJointsAndTheGrasp) {
  const auto command = std::make_unique<BodyCommand>();
  command->cartesian_type = CartesianCommandType::kVelocity;
  command->twist.linear_mps = {9, 9, 9};
  const JointRange joints[] = {{-0.3, 0.548}, {0.0, 1.0}};
  fill_body_command(grasping_output(), joints, 1, *command);
  EXPECT_EQ(command->cartesian_type, CartesianCommandType::kForce);
  EXPECT_EQ(command->wrench.force_n.y, 2);
  EXPECT_EQ(command->wrench.torque_nm.z, 6);
  EXPECT_EQ(command->pose.position_m.z, 0.3);
  EXPECT_EQ(command->twist.linear_mps.x, 0);
  ASSERT_EQ(command->joint_count, 2u);
  EXPECT_EQ(command->joints[0].type, JointCommandType::kPosition);
  EXPECT_DOUBLE_EQ(command->joints[0].value, -0.3 + 0.25 * 0.848);
  EXPECT_DOUBLE_EQ(command->joints[1].value, 0.25);
  ASSERT_EQ(command->actuator_count, 1u);
  EXPECT_EQ(command->actuate[0], 1);

  TeleopOutput open = grasping_output();
  open.grasp = false;
  fill_body_command(open, {}, 1, *command);
  EXPECT_EQ(command->joint_count, 0u);
  EXPECT_EQ(command->actuate[0], 0);
}

TEST(TeleopCommands, CountsStayWithinThePayloadsCapacity) {
  const auto command = std::make_unique<BodyCommand>();
  const std::vector<JointRange> joints(kMaxJointsPerBody + 5, JointRange{0, 1});
  fill_body_command(grasping_output(), joints, kMaxActuatorsPerBody + 3, *command);
  EXPECT_EQ(command->joint_count, kMaxJointsPerBody);
  EXPECT_EQ(command->actuator_count, kMaxActuatorsPerBody);
}

TEST(TeleopCommands, TheBodysWrenchIsLimitedKeepingItsDirection) {
  Wrench wrench{{300.0, 0.0, 400.0}, {0.0, -30.0, 0.0}};
  limit_wrench(wrench, {100.0, 10.0});
  EXPECT_NEAR(wrench.force_n.x, 60.0, 1e-12);
  EXPECT_NEAR(wrench.force_n.z, 80.0, 1e-12);
  EXPECT_NEAR(wrench.torque_nm.y, -10.0, 1e-12);
  Wrench small{{1.0, 2.0, 2.0}, {0.5, 0.0, 0.0}};
  limit_wrench(small, {100.0, 10.0});
  EXPECT_EQ(small.force_n.z, 2.0);
  limit_wrench(small, {});  // no limit
  EXPECT_EQ(small.torque_nm.x, 0.5);
}

TEST(TeleopCommands, TheDeviceGetsTheForceEnabled) {
  DeviceCommand command;
  command.gripper_force_n = 3;
  fill_device_command(grasping_output(), true, command);
  EXPECT_EQ(command.wrench.force_n.x, -1);
  EXPECT_EQ(command.wrench.force_n.z, 0.5);
  EXPECT_EQ(command.wrench.torque_nm.y, 0.1);
  EXPECT_EQ(command.gripper_force_n, 0);
  EXPECT_EQ(command.enable, 1);
}

TEST(TeleopCommands, TheForceIsDisabledWhileTheBodysStatesAreStale) {
  DeviceCommand command;
  fill_device_command(grasping_output(), false, command);
  EXPECT_EQ(command.enable, 0);
}

}  // namespace
}  // namespace afhub::teleop
