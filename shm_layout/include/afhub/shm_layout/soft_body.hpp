// SoftBodyMesh: a soft body's surface for a viewer, on two channels of the soft
// body's instance: {"afhub", <soft body channel>, "soft_faces"}, published once
// (keep-last history) with its triangles, and {"afhub", <soft body channel>,
// "soft_nodes"}, published at display rate with its node positions and no faces.
// Loaned at its real size, soft_body_mesh_bytes(face_count): node positions are a
// fixed array (a display-rate chunk is the same size every time), faces come last.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

struct SoftBodyMesh {
  static constexpr PayloadKind kKind = PayloadKind::kSoftBodyMesh;
  PayloadHeader header;
  std::uint32_t node_count{0};  // entries [0, node_count) of `nodes`
  std::uint32_t face_count{0};  // entries [0, face_count) of `faces`; 0 on "soft_nodes"
  std::array<std::array<float, 3>, kMaxSoftBodyNodes> nodes{};          // world frame, metres
  std::array<std::array<std::uint32_t, 3>, kMaxSoftBodyFaces> faces{};  // node indices
};

// Bytes of a SoftBodyMesh holding `faces` faces: what is loaned and published.
constexpr std::size_t soft_body_mesh_bytes(std::size_t faces) {
  return offsetof(SoftBodyMesh, faces) + faces * sizeof(std::array<std::uint32_t, 3>);
}

}  // namespace afhub
