// The law's output into BodyCommand and DeviceCommand (see teleop_commands.hpp).
#include "afhub/teleop/teleop_commands.hpp"

#include <algorithm>
#include <cmath>

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

namespace {

void limit_length(Vec3& v, double limit) noexcept {
  const double length = std::hypot(v.x, v.y, v.z);
  if (limit <= 0.0 || !(length > limit)) return;
  const double scale = limit / length;
  v = {v.x * scale, v.y * scale, v.z * scale};
}

}  // namespace

void limit_wrench(Wrench& wrench, const WrenchLimit& limit) noexcept {
  limit_length(wrench.force_n, limit.force_n);
  limit_length(wrench.torque_nm, limit.torque_nm);
}

void fill_device_command(const TeleopOutput& out, bool body_live, DeviceCommand& command) noexcept {
  command.wrench = out.device_wrench;
  command.gripper_force_n = 0.0;
  command.enable = body_live ? 1 : 0;
}

}  // namespace afhub::teleop
