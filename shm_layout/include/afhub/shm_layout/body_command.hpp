// BodyCommand: what a controller writes into one body's command slot
// (AMBF's afCommand: a Cartesian command and per-joint commands). The joints come
// last and a command is loaned at its real size, body_command_bytes(joint_count).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "afhub/shm_layout/geometry.hpp"
#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

// Values as in AMBF: FORCE=0, POSITION=1, VELOCITY=2.
enum class CartesianCommandType : std::uint8_t { kForce = 0, kPosition = 1, kVelocity = 2 };

enum class JointCommandType : std::uint8_t { kEffort = 0, kPosition = 1, kVelocity = 2 };

struct JointCommand {
  double value{0.0};  // N m or N, rad or m, rad/s or m/s, by type
  JointCommandType type{JointCommandType::kEffort};
  std::array<std::uint8_t, 7> reserved{};
};

struct BodyCommand {
  static constexpr PayloadKind kKind = PayloadKind::kBodyCommand;
  PayloadHeader header;
  CartesianCommandType cartesian_type{CartesianCommandType::kForce};
  // 1: written by a lockstep client, answering the state of step header.sim_step;
  // a lockstep physics waits for it before stepping (see `afhub run --lockstep`).
  // kLockstepKeep: an answer that changes nothing: the command in force stays (a
  // replay's step on which the recorded client sent nothing new).
  static constexpr std::uint8_t kLockstepKeep = 2;
  std::uint8_t lockstep{0};
  std::array<std::uint8_t, 2> reserved{};
  // Joint command i drives the i-th joint of the body's state; entries
  // [0, joint_count) are valid, the only ones in the chunk, and the list may be
  // shorter than the body's joints.
  std::uint32_t joint_count{0};
  Pose pose;      // target for kPosition
  Wrench wrench;  // applied for kForce, world frame
  Twist twist;    // target for kVelocity
  // The body's constraint actuators in file order: 1 holds whatever body touches the
  // actuator, 0 lets go; entries [0, actuator_count) are valid.
  std::uint32_t actuator_count{0};
  std::array<std::uint8_t, kMaxActuatorsPerBody> actuate{};
  std::array<JointCommand, kMaxJointsPerBody> joints{};  // last: sized by joint_count
};

// Bytes of a BodyCommand with `joints` joint commands: what is loaned and published.
constexpr std::size_t body_command_bytes(std::size_t joints) {
  return offsetof(BodyCommand, joints) + joints * sizeof(JointCommand);
}

// Copies a command at its real size (see copy_body_state); `to` holds at least
// from.joint_count joint commands.
inline void copy_body_command(const BodyCommand& from, BodyCommand& to) noexcept {
  std::memcpy(&to, &from, body_command_bytes(from.joint_count));
}

}  // namespace afhub
