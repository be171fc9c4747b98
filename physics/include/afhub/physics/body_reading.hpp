// What the simulation reads back for one body after a step: a plain value type of
// the physics core (the channel adapter turns it into the wire's BodyState).
#pragma once

#include <array>
#include <cstdint>

#include "afhub/physics/body_input.hpp"
#include "afhub/shm_layout/geometry.hpp"

namespace afhub::physics {

struct BodyReading {
  Pose pose;  // the body's mesh frame in the world (a soft body: its nodes' centre)
  Twist twist;
  Wrench wrench;  // applied in the last step
  // The net force of the last step's contacts on the body (world frame), and its
  // torque about the body's mesh frame origin (`pose`'s position); zero for a soft
  // body. contact_count: the contact points that pushed on it.
  Wrench contact_wrench;
  std::uint32_t contact_count = 0;
  double mass_kg = 0.0;
  Vec3 principal_inertia_kgm2;  // zero for a static body
  // Descendant joints in file order; entries [0, joint_count) are valid.
  std::uint32_t joint_count = 0;
  std::array<double, kBodyJointCapacity> joint_positions{};   // rad or m
  std::array<double, kBodyJointCapacity> joint_velocities{};  // rad/s or m/s
  std::array<double, kBodyJointCapacity> joint_efforts{};     // N m or N
  // Proximity-sensor rays in file order: distance to the first hit, -1 when none,
  // and the ray's range.
  std::uint32_t ray_count = 0;
  std::array<double, kBodyRayCapacity> ray_distances_m{};
  std::array<double, kBodyRayCapacity> ray_ranges_m{};
};

}  // namespace afhub::physics
