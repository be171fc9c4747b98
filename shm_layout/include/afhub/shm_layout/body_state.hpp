// BodyState: what the physics process publishes for one body every step
// (AMBF's afState: pose, twist, wrench, inertia and the body's descendant joints).
#pragma once

#include <array>
#include <cstdint>

#include "afhub/shm_layout/geometry.hpp"
#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

struct BodyState {
  static constexpr PayloadKind kKind = PayloadKind::kBodyState;
  PayloadHeader header;
  Pose pose;  // the body's mesh frame in the world
  Twist twist;
  Wrench wrench;  // the wrench applied to the body in the last step
  double mass_kg{0.0};
  Vec3 principal_inertia_kgm2;
  // Descendant joints in the catalog's order; entries [0, joint_count) are valid.
  std::uint32_t joint_count{0};
  // This body's command timeliness, as the physics counts it since it started
  // (modulo 2^32): steps taken under command, and those whose command answered the
  // state published just before (the command's header.sim_step + 1 == the step). A
  // controller reports the growth of commanded - answered as its late commands, so
  // that `afhub top` and `afhub status` show the physics' one count.
  std::uint32_t commanded_steps{0};
  std::array<double, kMaxJointsPerBody> joint_positions{};   // rad or m
  std::array<double, kMaxJointsPerBody> joint_velocities{};  // rad/s or m/s
  std::array<double, kMaxJointsPerBody> joint_efforts{};     // N m or N
  // Proximity sensors on this body, their rays in file order; entries
  // [0, sensor_ray_count) are valid. Distance to the first hit, or -1 when nothing
  // is within the sensor's range.
  std::uint32_t sensor_ray_count{0};
  std::uint32_t answered_steps{0};  // see commanded_steps
  std::array<double, kMaxSensorRaysPerBody> sensor_distances_m{};
};

}  // namespace afhub
