// Triangle meshes read through assimp (STL, OBJ, DAE and the rest it knows), and
// their mass properties, used when a body gives no inertia or inertial offset.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "afhub/physics/model.hpp"

namespace afhub::physics {

struct TriangleMesh {
  std::vector<std::array<double, 3>> vertices;  // in the mesh frame, scaled
  std::vector<std::array<unsigned, 3>> triangles;
};

// Bounds on what a mesh may be: larger files are refused before parsing, and
// larger meshes after it. A 256 MB binary STL holds 5 million triangles; a
// collision mesh has a few thousand.
inline constexpr std::uintmax_t kMaxMeshFileBytes = 256u << 20;
inline constexpr std::size_t kMaxMeshTriangles = 10'000'000;
inline constexpr std::size_t kMaxMeshVertices = 30'000'000;

// Reads every mesh of the file into one, node transforms applied, scaled by `scale`.
// Throws afhub::Error naming the file when it cannot be read (missing, not a regular
// file, unreadable, past the bounds above), assimp cannot parse it, it has no
// triangles, or a vertex is not finite. assimp parses in a child process
// (afhub-mesh-reader, beside this program or on PATH) under limits on memory (2 GB),
// CPU time (20 s a file) and time without progress (40 s): a file that crashes it,
// hangs it or exceeds them is an error too, and opens only regular files, the ones
// a mesh names (an OBJ's materials) included.
TriangleMesh load_mesh(const std::string& path, double scale);

// load_mesh for the block at `where` (`owner`: "body 'BODY base'"): its error
// starts with that location.
TriangleMesh load_body_mesh(const std::string& path, double scale, const SourceLocation& where,
                            const std::string& owner);

// A mesh that a block of a model names.
struct MeshRequest {
  std::string path;
  Vec3 scale{1.0, 1.0, 1.0};  // per axis
  SourceLocation where;
  std::string owner;  // "body 'BODY base'"
};

// A mesh file at one scale: what is read once however many bodies name it.
using MeshKey = std::tuple<std::string, double, double, double>;
inline MeshKey mesh_key(const std::string& path, const Vec3& scale) {
  return {path, scale.x, scale.y, scale.z};
}

// load_body_mesh for each request, in their order, all read by one child process
// (each file once, whatever its scales): what a model's loading costs is one process
// start, not one per mesh. The meshes read last (up to 64 MiB) are kept while their
// files are unchanged, for the next call (`afhub check` reads a model's meshes, then
// builds its simulation). Throws the error of the first that cannot be used.
std::vector<TriangleMesh> load_body_meshes(const std::vector<MeshRequest>& requests);

// A request's mesh, or why it cannot be used (the mesh's own error, not located).
struct MeshOrError {
  std::optional<TriangleMesh> mesh;
  std::string error;
};
// load_body_meshes, without throwing for a mesh that cannot be used.
std::vector<MeshOrError> try_load_body_meshes(const std::vector<MeshRequest>& requests);

// Reads every mesh the model names once (what `afhub check` does, so that it
// finds the mesh problems `afhub run` would), and checks each soft body's against
// check_soft_body_mesh; returns how many were read.
std::size_t check_meshes(const Model& model);

// Throws afhub::Error at the soft body's block when its mesh would make more nodes
// (the highest vertex index used, plus one) or faces than the hub's soft body payload
// carries (kMaxSoftBodyNodes, kMaxSoftBodyFaces). Checked before Bullet builds the
// body: its builder allocates nodes x nodes flags, gigabytes past 40 000 nodes, and
// overflows an int (a crash) past 46 340.
void check_soft_body_mesh(const SoftBodySpec& soft, const TriangleMesh& mesh);

// A 3x3 matrix, row-major.
using Matrix3 = std::array<double, 9>;

// Of a closed mesh of uniform density: volume, centroid, and the full inertia tensor
// about the centroid per kg, in the mesh frame (products of inertia included). Open
// or degenerate meshes (volume ~ 0) fall back to the vertices' bounding box.
struct MeshMassProperties {
  double volume_m3 = 0.0;
  std::array<double, 3> centroid_m{};
  Matrix3 inertia_per_kg{};  // m^2
  bool from_bounding_box = false;
};
MeshMassProperties mass_properties(const TriangleMesh& mesh);

// The mesh's inertia per kg about `point`, seen in a frame turned by `frame` (both
// in the mesh frame), diagonalised: its principal moments, and the rotation from
// `frame` to the principal axes (a proper rotation; its columns are the axes).
struct PrincipalInertia {
  std::array<double, 3> moments_per_kg{};  // m^2
  Matrix3 axes{};
};
PrincipalInertia principal_inertia(const MeshMassProperties& mesh,
                                   const std::array<double, 3>& point, const Matrix3& frame);

}  // namespace afhub::physics
