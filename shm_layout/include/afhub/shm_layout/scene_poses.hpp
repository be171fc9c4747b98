// ScenePoses: every body's pose and joint positions in one payload, for a viewer,
// on {"afhub", <world instance>, "scene_poses"}. The physics publishes it at display
// rate (kViewerRateHz, not the step rate) and only while something reads it, so
// that a viewer costs the real-time loop one small publish every few steps instead
// of one more reader on every body's 1 kHz state channel. Bodies are in the scene
// description's order (entry b is SceneDescription.bodies[b]); passive bodies too.
// Loaned at its real size, scene_poses_bytes(body_count, joint_value_count).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

// A viewer draws at 30-60 Hz: the physics publishes what it reads (this, and soft
// bodies' nodes) at this rate; a faster feed would be read by no one.
inline constexpr double kViewerRateHz = 60.0;

struct ScenePose {
  std::array<float, 3> position_m{};                     // the mesh frame, world frame
  std::array<float, 4> orientation_xyzw{0, 0, 0, 1.0F};  // unit quaternion
  // The body's state's joints (those below it, as BodyState.joints) are entries
  // [first_joint, first_joint + joint_count) of joint_positions_in(); 0 when passive.
  std::uint32_t first_joint{0};
  std::uint32_t joint_count{0};
};

struct ScenePoses {
  static constexpr PayloadKind kKind = PayloadKind::kScenePoses;
  PayloadHeader header;
  std::uint32_t body_count{0};
  std::uint32_t joint_value_count{0};
  // Only the first body_count entries are in the chunk; joint_value_count floats
  // (rad or m) follow them: a small chunk for a small scene, cheap to fill.
  std::array<ScenePose, kMaxSceneBodies> bodies{};
};

// Bytes of a ScenePoses holding `bodies` bodies and `joint_values` joint positions:
// what is loaned and published.
constexpr std::size_t scene_poses_bytes(std::size_t bodies, std::size_t joint_values = 0) {
  return offsetof(ScenePoses, bodies) + bodies * sizeof(ScenePose) + joint_values * sizeof(float);
}

// The joint positions of a ScenePoses whose body_count is set (and, when read,
// checked with check_payload).
inline float* joint_positions_in(ScenePoses& poses) {
  return reinterpret_cast<float*>(reinterpret_cast<char*>(&poses) +
                                  scene_poses_bytes(poses.body_count));
}
inline const float* joint_positions_in(const ScenePoses& poses) {
  return reinterpret_cast<const float*>(reinterpret_cast<const char*>(&poses) +
                                        scene_poses_bytes(poses.body_count));
}

}  // namespace afhub
