// The law's output as the two commands a teleoperation cycle writes: the simulated
// body's BodyCommand and the device's DeviceCommand. Headers (stamps, sequence,
// lockstep) are the caller's.
#pragma once

#include <cstdint>
#include <span>

#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/device.hpp"
#include "afhub/teleop/teleop_law.hpp"

namespace afhub::teleop {

// A gripper joint's range: the gripper value 0 (closed) .. 1 (open) maps onto it, as
// AMBF's simulated device does.
struct JointRange {
  double lower{0.0};
  double upper{0.0};
};

// The body command: a kForce Cartesian command with the law's wrench (world frame);
// the target pose rides along for viewers. Joint i (of the body's descendant joints)
// gets a position command at the gripper value over `gripper_joints[i]` (none past
// kMaxJointsPerBody; pass none when "enable joint control" is false). The first
// `actuator_count` constraint actuators hold while the gripper grasps.
void fill_body_command(const TeleopOutput& out, std::span<const JointRange> gripper_joints,
                       std::uint32_t actuator_count, BodyCommand& command) noexcept;

// The most force and torque a body takes (the physics refuses a command beyond its
// bounds, and the body would then fall free); 0: no limit.
struct WrenchLimit {
  double force_n{0.0};
  double torque_nm{0.0};
};

// Scales the wrench's force and torque down to `limit`, each keeping its direction.
void limit_wrench(Wrench& wrench, const WrenchLimit& limit) noexcept;

// The device command: the law's force and torque (device frame), no gripper force,
// force enabled only while `body_live` (the body's states are fresh: the driver then
// applies no force, and ramps it in again once enabled).
void fill_device_command(const TeleopOutput& out, bool body_live, DeviceCommand& command) noexcept;

}  // namespace afhub::teleop
