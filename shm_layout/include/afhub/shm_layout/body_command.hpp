// BodyCommand: what a controller writes into one body's command slot
// (AMBF's afCommand: a Cartesian command and per-joint commands).
#pragma once

#include <array>
#include <cstdint>

#include "afhub/shm_layout/geometry.hpp"
#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

// Values as in AMBF: FORCE=0, POSITION=1, VELOCITY=2.
enum class CartesianCommandType : std::uint8_t { kForce = 0, kPosition = 1, kVelocity = 2 };

enum class JointCommandType : std::uint8_t { kEffort = 0, kPosition = 1, kVelocity = 2 };

struct BodyCommand {
  static constexpr PayloadKind kKind = PayloadKind::kBodyCommand;
  PayloadHeader header;
  CartesianCommandType cartesian_type{CartesianCommandType::kForce};
  // 1: written by a lockstep client, answering the state of step header.sim_step;
  // a lockstep physics waits for it before stepping (see `afhub run --lockstep`).
  std::uint8_t lockstep{0};
  std::array<std::uint8_t, 2> reserved{};
  // Joint command i drives the i-th joint of the body's state; entries
  // [0, joint_count) are valid and the list may be shorter than the body's joints.
  std::uint32_t joint_count{0};
  Pose pose;      // target for kPosition
  Wrench wrench;  // applied for kForce, world frame
  Twist twist;    // target for kVelocity
  std::array<double, kMaxJointsPerBody> joint_values{};
  std::array<JointCommandType, kMaxJointsPerBody> joint_types{};
  // The body's constraint actuators in file order: 1 holds whatever body touches the
  // actuator, 0 lets go; entries [0, actuator_count) are valid.
  std::uint32_t actuator_count{0};
  std::array<std::uint8_t, kMaxActuatorsPerBody> actuate{};
};

}  // namespace afhub
