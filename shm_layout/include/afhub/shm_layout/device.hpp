// Device channels: a haptic or input device's driver process publishes DeviceState
// every cycle on {"afhub", "device/<name>", "state"} and applies the newest
// DeviceCommand from {"afhub", "device/<name>", "command"}. The device's spec
// travels in every state (it is small), so a late reader needs nothing else.
#pragma once

#include <array>
#include <cstdint>

#include "afhub/shm_layout/geometry.hpp"
#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

// Degrees of freedom a device senses or actuates, as bits.
enum DeviceAxes : std::uint32_t {
  kDeviceTranslation = 1U << 0,  // x, y, z
  kDeviceRotation = 1U << 1,     // roll, pitch, yaw
  kDeviceGripper = 1U << 2,
};

// What the device is, once: CHAI3D's device specification, in SI units.
struct DeviceSpec {
  std::array<char, 64> model{};   // "Novint Falcon", "SpaceMouse Compact", "virtual"
  std::array<char, 64> serial{};  // empty when the device has none
  double max_force_n{0.0};        // the driver never applies more
  double max_torque_nm{0.0};
  double max_gripper_force_n{0.0};
  double max_stiffness_npm{0.0};   // the stiffest spring it renders stably
  double workspace_radius_m{0.0};  // reach from its centre
  std::uint32_t sensed{0};         // DeviceAxes bits
  std::uint32_t actuated{0};       // DeviceAxes bits: the forces it can apply
  std::uint32_t button_count{0};
  std::uint32_t reserved{0};
};

// Why the driver applies no force now.
enum class ForceGate : std::uint8_t {
  kApplying = 0,   // the newest command's force (clamped, ramping in)
  kDisabled = 1,   // the newest command's enable flag is off
  kNoCommand = 2,  // no command yet, or its writer is gone
  kWatchdog = 3,   // no fresh command within the driver's timeout
  kStopping = 4,   // the driver is exiting, or the hub went away
};

struct DeviceState {
  static constexpr PayloadKind kKind = PayloadKind::kDeviceState;
  PayloadHeader header;
  DeviceSpec spec;
  Pose pose;       // in the device's own frame, metres
  Twist velocity;  // in the device's own frame
  double gripper_angle_rad{0.0};
  std::uint32_t buttons{0};  // bit i: button i pressed
  ForceGate gate{ForceGate::kNoCommand};
  std::uint8_t reserved[3]{};
  Wrench applied;  // what the device applies now (after clamp and ramp)
  double applied_gripper_force_n{0.0};
  // The command the applied force comes from: its sequence and stamp, so that a
  // client can measure command-to-force latency. 0 when there is none.
  std::uint64_t command_sequence{0};
  std::int64_t command_stamp_ns{0};
};

struct DeviceCommand {
  static constexpr PayloadKind kKind = PayloadKind::kDeviceCommand;
  PayloadHeader header;
  Wrench wrench;  // wanted force and torque, device frame
  double gripper_force_n{0.0};
  std::uint8_t enable{0};  // 0: no force, whatever the wrench says
  std::uint8_t reserved[7]{};
};

}  // namespace afhub
