// Mesh files read in a child process, afhub-mesh-reader (physics/mesh_reader/main.cpp):
// assimp parses there, under limits on memory, CPU time and file size, and a file that
// crashes or hangs it ends that process, never this one. Its records (mesh_wire.hpp)
// are checked before use.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace afhub::physics {

// A mesh as read, unscaled: every index names one of its vertices, and there are no
// more than kMaxMeshVertices and kMaxMeshTriangles (mesh.hpp). Values are not checked.
struct RawMesh {
  std::vector<float> xyz;                // 3 per vertex
  std::vector<std::uint32_t> triangles;  // 3 per triangle
};

// One file's outcome: its mesh, or why it cannot be used ("PATH: error: ...").
struct MeshReadResult {
  RawMesh mesh;
  std::string error;  // empty when read
};

struct MeshReaderOptions {
  std::string program;  // empty: mesh_reader_program()
  // Stopped when the reader writes no record for this long.
  std::chrono::milliseconds time_per_mesh{std::chrono::seconds(40)};
};

// Reads `paths` in order, with as few reader processes as it can: one for all,
// another after one dies on a file. Throws afhub::Error when no reader can be started.
std::vector<MeshReadResult> read_mesh_files(const std::vector<std::string>& paths,
                                            const MeshReaderOptions& options = {});

// afhub-mesh-reader: $AFHUB_MESH_READER, else beside this executable, else on PATH.
std::string mesh_reader_program();

}  // namespace afhub::physics
