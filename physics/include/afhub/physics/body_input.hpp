// What the simulation takes for one body each step: a Cartesian input (force,
// pose target or velocity), per-joint inputs for the body's descendant joints in
// order, and its constraint actuators engaged or released. A plain value type of
// the physics core (it knows no wire format): the channel adapter copies a command
// out of shared memory into one, the core checks it (input_problem), then applies it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "afhub/shm_layout/geometry.hpp"

namespace afhub::physics {

// Capacities of one body's inputs and readings.
inline constexpr std::size_t kBodyJointCapacity = 64;    // descendant joints
inline constexpr std::size_t kBodyRayCapacity = 32;      // proximity-sensor rays
inline constexpr std::size_t kBodyActuatorCapacity = 8;  // constraint actuators

// As in AMBF: FORCE, POSITION (through the body's PID), VELOCITY.
enum class CartesianMode : std::uint8_t { kForce = 0, kPosition = 1, kVelocity = 2 };
// Per joint: EFFORT, POSITION (through the joint's PID), VELOCITY (the joint motor).
enum class JointMode : std::uint8_t { kEffort = 0, kPosition = 1, kVelocity = 2 };

struct BodyInput {
  CartesianMode cartesian = CartesianMode::kForce;
  Pose target_pose;  // the mesh frame's target, for kPosition
  Wrench wrench;     // world frame, for kForce
  Twist twist;       // for kVelocity
  // Entries [0, joint_count) are valid; the list may be shorter than the body's joints.
  std::uint32_t joint_count = 0;
  std::array<JointMode, kBodyJointCapacity> joint_modes{};
  std::array<double, kBodyJointCapacity> joint_values{};
  // The body's actuators in file order; entries [0, actuator_count) are valid.
  std::uint32_t actuator_count = 0;
  std::array<bool, kBodyActuatorCapacity> engage{};
};

// nullptr when `input` can be applied to a body with `joint_count` joints and
// `actuator_count` actuators; else what is wrong with it (NaN or Inf, a joint or an
// actuator beyond the body's, an unknown mode).
const char* input_problem(const BodyInput& input, std::uint32_t joint_count,
                          std::uint32_t actuator_count = 0) noexcept;

}  // namespace afhub::physics
