// What the simulation takes for one body each step: a Cartesian input (force,
// pose target or velocity), per-joint inputs for the body's descendant joints in
// order, and its constraint actuators engaged or released. A plain value type of
// the physics core (it knows no wire format): the channel adapter copies a command
// out of shared memory into one, the core checks it (input_problem), then applies it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "afhub/shm_layout/geometry.hpp"

namespace afhub::physics {

// Capacities of one body's inputs and readings.
inline constexpr std::size_t kBodyJointCapacity = 1024;  // descendant joints
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

// The physical bounds a body's input is held to, derived from the model when the
// simulation is built (Simulation::input_bounds); a finite value beyond them (1e308)
// would make the world NaN, so it is refused like a NaN. With g = 9.81 m/s^2, M the
// mass of the body and of everything below it (at least 1 kg), R the reach of the
// scene (the farthest body origin, or the enclosure's half diagonal, at least 1 m):
//   workspace_m    R + 10 m: a pose target farther than that from the world origin
//   force_n        M * 100 g: a Cartesian force of 100 g on what the body carries
//   torque_nm      force_n * R
//   linear_mps     max(10 m/s, P_linear * 2 workspace): the body's own position PID
//                  (velocity output) never asks for more anywhere in the workspace
//   angular_radps  max(20 pi rad/s, P_angular * 2 pi)
// Per descendant joint, in order, with m the mass the joint carries (its child and
// everything below it):
//   joint_effort   max(max motor impulse / dt, 10 m g R) for a rotational joint
//                  (N m: ten times the largest gravity load it carries at full
//                  reach), max(max motor impulse / dt, 10 m g) for a linear one (N);
//                  an effort within it is applied capped to max motor impulse / dt
//   joint_velocity max(20 pi rad/s, P * 2 pi) rotational, max(10 m/s, P * workspace)
//                  linear, with P the joint PID's gain
//   joint_position 100 rad (16 turns) rotational, 1e9 rad continuous (it counts
//                  its turns), the workspace linear
struct InputBounds {
  double workspace_m = 0.0;
  double force_n = 0.0, torque_nm = 0.0;
  double linear_mps = 0.0, angular_radps = 0.0;
  // One entry per descendant joint, sized when the simulation is built.
  std::vector<double> joint_effort, joint_velocity, joint_position;
};

// nullptr when `input` can be applied to a body with `joint_count` joints and
// `actuator_count` actuators; else what is wrong with it (NaN or Inf, a joint or an
// actuator beyond the body's, an unknown mode).
const char* input_problem(const BodyInput& input, std::uint32_t joint_count,
                          std::uint32_t actuator_count = 0) noexcept;

}  // namespace afhub::physics
