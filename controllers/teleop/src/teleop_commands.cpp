// The law's output into BodyCommand and DeviceCommand (see teleop_commands.hpp).
#include "afhub/teleop/teleop_commands.hpp"

#include <algorithm>

namespace afhub::teleop {

void fill_body_command(const TeleopOutput& out, std::span<const JointRange> gripper_joints,
                       std::uint32_t actuator_count, BodyCommand& command) noexcept {
  command.cartesian_type = CartesianCommandType::kForce;
  command.wrench = out.body_wrench;
  command.pose = out.body_target;
  command.twist = {};
  const std::size_t joints = std::min(gripper_joints.size(), kMaxJointsPerBody);
  command.joint_count = static_cast<std::uint32_t>(joints);
  for (std::size_t j = 0; j < joints; ++j) {
    const JointRange& range = gripper_joints[j];
    command.joints[j].type = JointCommandType::kPosition;
    command.joints[j].value = range.lower + out.gripper * (range.upper - range.lower);
  }
  command.actuator_count =
      std::min(actuator_count, static_cast<std::uint32_t>(kMaxActuatorsPerBody));
  for (std::uint32_t a = 0; a < command.actuator_count; ++a) command.actuate[a] = out.grasp;
}

void fill_device_command(const TeleopOutput& out, DeviceCommand& command) noexcept {
  command.wrench = out.device_wrench;
  command.gripper_force_n = 0.0;
  command.enable = 1;
}

}  // namespace afhub::teleop
