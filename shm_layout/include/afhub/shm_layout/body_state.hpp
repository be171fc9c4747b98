// BodyState: what the physics process publishes for one body every step
// (AMBF's afState: pose, twist, wrench, inertia and the body's descendant joints;
// and the contact wrench, which AMBF does not publish).
// The joints come last and a state is loaned at its real size, body_state_bytes(
// joint_count): only entries [0, joint_count) exist in the chunk.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "afhub/shm_layout/geometry.hpp"
#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

// Bytes of the reason a body's state gives for the last command refused, its NUL
// included (the physics' reasons name a joint and its bound in fewer).
inline constexpr std::size_t kRefusalReasonSize = 160;

struct JointSample {
  double position{0.0};  // rad or m
  double velocity{0.0};  // rad/s or m/s
  double effort{0.0};    // N m or N
};

struct BodyState {
  static constexpr PayloadKind kKind = PayloadKind::kBodyState;
  PayloadHeader header;
  Pose pose;  // the body's mesh frame in the world
  Twist twist;
  Wrench wrench;  // the wrench applied to the body in the last step
  // The net wrench of the last step's contacts on the body (rigid bodies, from the
  // physics' contact manifolds: normal and friction impulses over the step), world
  // frame; its torque is about the mesh frame's origin (pose.position_m). Zero with
  // no contact, and for a soft body.
  Wrench contact_wrench;
  double mass_kg{0.0};
  Vec3 principal_inertia_kgm2;
  // When this step was due on its physics' clock (CLOCK_MONOTONIC ns): the physics
  // steps on the grid step_due_ns + k dt, and a free-running controller wakes in phase
  // with it (controllers/controller.hpp). 0 when the physics is not paced by the
  // clock (--fast) or the state was not published on this machine (a DDS mirror).
  std::int64_t step_due_ns{0};
  // The step whose state the command in force during this step answered (that
  // command's header.sim_step), or -1 with none in force (none yet, its watchdog
  // expired, or the world reset): header.sim_step - 1 - command_answered_step is how
  // many steps old the state it answered was. A lockstep replay applies each recorded
  // command at the step it took effect in (afhub play --commands-into-physics).
  std::int64_t command_answered_step{-1};
  // Descendant joints in the catalog's order; entries [0, joint_count) are valid
  // and the only ones in the chunk.
  std::uint32_t joint_count{0};
  // This body's command timeliness, as the physics counts it since it started
  // (modulo 2^32): steps taken under command, and those whose command answered the
  // state published just before (the command's header.sim_step + 1 == the step). A
  // controller reports the growth of commanded - answered as its late commands, so
  // that `afhub top` and `afhub status` show the physics' one count.
  std::uint32_t commanded_steps{0};
  // Proximity sensors on this body, their rays in file order; entries
  // [0, sensor_ray_count) of sensor_distances_m and sensor_ranges_m are valid. Distance
  // to the first hit, or -1 when nothing is within the sensor's range. The catalog
  // names the sensor of each ray (BodyInfo.sensor_ray_count).
  std::uint32_t sensor_ray_count{0};
  std::uint32_t answered_steps{0};  // see commanded_steps
  std::uint32_t contact_count{0};   // contact points that pushed on the body in the last step
  // The commands for this body the physics refused (NaN or Inf, beyond the body's
  // bounds, more joints than it has: never applied), counted since it started (modulo
  // 2^32), and the last one's sender and reason (NUL-terminated), so that the sender
  // can say why: `afhub cmd` stops with it.
  std::uint32_t refused_commands{0};
  std::uint32_t refused_command_pid{0};
  std::array<char, kRefusalReasonSize> refusal_reason{};
  std::array<double, kMaxSensorRaysPerBody> sensor_distances_m{};
  // Each ray's range, m: with its distance, what AMBF's sensor reports (its normalized
  // measurement), so that a reader needs no model file.
  std::array<double, kMaxSensorRaysPerBody> sensor_ranges_m{};
  std::array<JointSample, kMaxJointsPerBody> joints{};  // last: sized by joint_count
};

// Bytes of a BodyState with `joints` joints: what is loaned and published.
constexpr std::size_t body_state_bytes(std::size_t joints) {
  return offsetof(BodyState, joints) + joints * sizeof(JointSample);
}

// Copies a state at its real size: a chunk holds no joints past its joint_count, so
// `*to = from` would read or write past it. `to` holds at least from.joint_count joints.
inline void copy_body_state(const BodyState& from, BodyState& to) noexcept {
  std::memcpy(&to, &from, body_state_bytes(from.joint_count));
}

}  // namespace afhub
