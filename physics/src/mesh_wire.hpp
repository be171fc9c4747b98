// What afhub-mesh-reader writes on its standard output for the physics to read back
// (mesh_reader.cpp): one record per mesh file, in the order of its arguments. The
// reader parses untrusted files, so its records are untrusted too: the physics checks
// every header and every value it copies out of them.
#pragma once

#include <cstddef>
#include <cstdint>

namespace afhub::physics::mesh_wire {

inline constexpr std::uint32_t kMagic = 0x4853454d;  // "MESH"

enum Status : std::uint32_t { kRead = 0, kRefused = 1 };

// Followed, when kRead, by vertex_count * 3 floats (x, y, z, unscaled, in the mesh
// frame) and then triangle_count * 3 uint32 vertex indices; when kRefused, by
// message_bytes of text saying why (counts 0).
struct Header {
  std::uint32_t magic = kMagic;
  std::uint32_t index = 0;  // which argument
  std::uint32_t status = kRead;
  std::uint32_t message_bytes = 0;
  std::uint64_t vertex_count = 0;
  std::uint64_t triangle_count = 0;
};
static_assert(sizeof(Header) == 32);

inline constexpr std::size_t kMaxMessageBytes = 2048;

// The limits the reader puts on itself before it opens a file (the physics also
// stops it after a wall-clock time without a record).
inline constexpr std::uint64_t kAddressSpaceBytes = std::uint64_t{2} << 30;
inline constexpr unsigned kCpuSecondsPerMesh = 20;

}  // namespace afhub::physics::mesh_wire
