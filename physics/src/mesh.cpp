// Mesh reading (in afhub-mesh-reader, see mesh_reader.hpp) and mass properties (see mesh.hpp).
#include "afhub/physics/mesh.hpp"

#include <sys/stat.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>

#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "afhub/yaml/input_file.hpp"
#include "mesh_reader.hpp"

namespace afhub::physics {
namespace {

// A vertex farther than this from its mesh's origin is garbage, not a part.
constexpr double kMaxVertexM = 1e5;

// The error of the block that names a mesh: its location, then the mesh's own.
Error block_error(const MeshRequest& request, const std::string& error) {
  return Error(request.where.str() + ": error: " + request.owner +
               ": its mesh cannot be used: " + error);
}

// `raw` scaled, every vertex checked.
TriangleMesh scaled(const RawMesh& raw, const std::string& path, const Vec3& scale) {
  TriangleMesh mesh;
  mesh.vertices.reserve(raw.xyz.size() / 3);
  for (std::size_t v = 0; v < raw.xyz.size(); v += 3) {
    const float* p = &raw.xyz[v];
    const std::array<double, 3> point{p[0] * scale.x, p[1] * scale.y, p[2] * scale.z};
    for (double component : point)
      if (!std::isfinite(component) || std::abs(component) > kMaxVertexM)
        throw Error(path + ": error: vertex " + std::to_string(v / 3) + " is (" +
                    std::to_string(p[0]) + ", " + std::to_string(p[1]) + ", " +
                    std::to_string(p[2]) +
                    "): not a finite point within 100 km of the origin; repair the mesh");
    mesh.vertices.push_back(point);
  }
  // A mirrored mesh (an odd number of negative axes) turns its triangles inside out:
  // each is wound back the other way, so that its normal faces out again.
  const bool mirrored = scale.x * scale.y * scale.z < 0;
  mesh.triangles.reserve(raw.triangles.size() / 3);
  for (std::size_t t = 0; t < raw.triangles.size(); t += 3)
    mesh.triangles.push_back(
        mirrored ? std::array{raw.triangles[t], raw.triangles[t + 2], raw.triangles[t + 1]}
                 : std::array{raw.triangles[t], raw.triangles[t + 1], raw.triangles[t + 2]});
  if (mesh.triangles.empty())
    throw Error(path + ": error: the mesh has no triangles; export it with faces");
  return mesh;
}

// A file as it was when read: another file at its path, or a change, is read again.
struct FileIdentity {
  bool known = false;
  dev_t device = 0;
  ino_t inode = 0;
  off_t size = 0;
  std::int64_t modified_ns = 0, changed_ns = 0;
  bool operator==(const FileIdentity&) const = default;
};

FileIdentity identity_of(const std::string& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) return {};
  auto ns = [](const timespec& t) { return std::int64_t{t.tv_sec} * 1'000'000'000 + t.tv_nsec; };
  return {true,           status.st_dev,      status.st_ino,
          status.st_size, ns(status.st_mtim), ns(status.st_ctim)};
}

struct KeptMesh {
  FileIdentity identity;
  std::shared_ptr<const RawMesh> mesh;
};

// The meshes read last, kept while their files are unchanged: `afhub check` reads a
// model's meshes, then builds its simulation, which reads the collision meshes again.
// At most 64 MiB of them: the oldest batches are forgotten first.
constexpr std::size_t kMaxKeptBytes = 64u << 20;
std::mutex kept_mutex;
std::map<std::string, KeptMesh> kept;
std::size_t kept_bytes = 0;

std::size_t bytes_of(const RawMesh& mesh) {
  return mesh.xyz.size() * sizeof(float) + mesh.triangles.size() * sizeof(std::uint32_t);
}

std::shared_ptr<const RawMesh> kept_mesh(const std::string& path, const FileIdentity& identity) {
  const std::lock_guard lock(kept_mutex);
  const auto found = kept.find(path);
  if (!identity.known || found == kept.end() || !(found->second.identity == identity))
    return nullptr;
  return found->second.mesh;
}

void keep_meshes(const std::map<std::string, KeptMesh>& batch) {
  std::size_t bytes = 0;
  for (const auto& [path, entry] : batch) bytes += bytes_of(*entry.mesh);
  const std::lock_guard lock(kept_mutex);
  if (kept_bytes + bytes > kMaxKeptBytes) {
    kept.clear();
    kept_bytes = 0;
  }
  if (bytes > kMaxKeptBytes) return;
  for (const auto& [path, entry] : batch) {
    if (!entry.identity.known) continue;
    if (auto old = kept.find(path); old != kept.end()) {
      kept_bytes -= bytes_of(*old->second.mesh);
      kept.erase(old);
    }
    kept.emplace(path, entry);
    kept_bytes += bytes_of(*entry.mesh);
  }
}

}  // namespace

TriangleMesh load_mesh(const std::string& path, double scale) {
  return load_body_meshes({{path, uniform_scale(scale), {}, ""}}).front();
}

TriangleMesh load_body_mesh(const std::string& path, double scale, const SourceLocation& where,
                            const std::string& owner) {
  return load_body_meshes({{path, uniform_scale(scale), where, owner}}).front();
}

std::vector<MeshOrError> try_load_body_meshes(const std::vector<MeshRequest>& requests) {
  // Each file checked here first (what it is, its size), then taken from the last
  // batch's meshes or read once in the reader.
  std::map<std::string, std::string> refused;  // path -> error
  std::map<std::string, KeptMesh> found;       // path -> mesh
  std::vector<std::string> files;
  std::vector<FileIdentity> identities;
  for (const MeshRequest& request : requests) {
    const std::string& path = request.path;
    if (refused.count(path) || found.count(path) ||
        std::find(files.begin(), files.end(), path) != files.end())
      continue;
    try {
      yaml::check_input_file(path, kMaxMeshFileBytes, "a mesh (STL, OBJ, DAE, ...)");
    } catch (const Error& error) {
      refused.emplace(path, error.what());
      continue;
    }
    const FileIdentity identity = identity_of(path);
    if (auto kept = kept_mesh(path, identity)) {
      found.emplace(path, KeptMesh{identity, kept});
      continue;
    }
    files.push_back(path);
    identities.push_back(identity);
  }
  std::vector<MeshReadResult> read = read_mesh_files(files);
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (!read[i].error.empty())
      refused.emplace(files[i], read[i].error);
    else
      found.emplace(files[i], KeptMesh{identities[i],
                                       std::make_shared<const RawMesh>(std::move(read[i].mesh))});
  }
  keep_meshes(found);
  std::vector<MeshOrError> meshes(requests.size());
  for (std::size_t i = 0; i < requests.size(); ++i) {
    const MeshRequest& request = requests[i];
    try {
      if (auto was_refused = refused.find(request.path); was_refused != refused.end())
        throw Error(was_refused->second);
      meshes[i].mesh = scaled(*found.at(request.path).mesh, request.path, request.scale);
    } catch (const Error& error) {
      meshes[i].error = error.what();
    }
  }
  return meshes;
}

std::vector<TriangleMesh> load_body_meshes(const std::vector<MeshRequest>& requests) {
  std::vector<MeshOrError> read = try_load_body_meshes(requests);
  std::vector<TriangleMesh> meshes;
  for (std::size_t i = 0; i < requests.size(); ++i) {
    // load_mesh's errors name the file alone; a block's say where it is named.
    if (!read[i].mesh && !requests[i].owner.empty()) throw block_error(requests[i], read[i].error);
    if (!read[i].mesh) throw Error(read[i].error);
    meshes.push_back(std::move(*read[i].mesh));
  }
  return meshes;
}

std::size_t check_meshes(const Model& model) {
  std::map<MeshKey, std::size_t> request_of;
  std::vector<MeshRequest> requests;
  auto add = [&](const std::string& path, const Vec3& scale, const SourceLocation& where,
                 const std::string& owner) {
    if (!path.empty() && request_of.try_emplace(mesh_key(path, scale), requests.size()).second)
      requests.push_back({path, scale, where, owner});
  };
  for (const BodySpec& body : model.bodies) {
    const std::string owner = "body '" + body.identifier + "'";
    add(body.collision_mesh, uniform_scale(body.scale), body.where, owner);
    for (const PlacedMesh& part : body.collision_mesh_parts)
      add(part.path, part.scale, body.where, owner);
    add(body.visual_mesh, uniform_scale(body.scale), body.where, owner + " (visual)");
    for (const PlacedMesh& part : body.visual_mesh_parts)
      add(part.path, part.scale, body.where, owner + " (visual)");
  }
  for (const SoftBodySpec& soft : model.soft_bodies)
    add(soft.mesh, uniform_scale(soft.scale), soft.where, "soft body '" + soft.identifier + "'");
  const std::vector<TriangleMesh> meshes = load_body_meshes(requests);
  for (const SoftBodySpec& soft : model.soft_bodies)
    if (!soft.mesh.empty())
      check_soft_body_mesh(soft,
                           meshes[request_of.at(mesh_key(soft.mesh, uniform_scale(soft.scale)))]);
  return requests.size();
}

void check_soft_body_mesh(const SoftBodySpec& soft, const TriangleMesh& mesh) {
  std::size_t nodes = 0;
  for (const auto& triangle : mesh.triangles)
    for (unsigned vertex : triangle) nodes = std::max<std::size_t>(nodes, vertex + std::size_t{1});
  if (nodes <= kMaxSoftBodyNodes && mesh.triangles.size() <= kMaxSoftBodyFaces) return;
  throw Error(soft.where.str() + ": error: soft body '" + soft.identifier + "' has " +
              std::to_string(nodes) + " nodes and " + std::to_string(mesh.triangles.size()) +
              " faces; afhub takes at most " + std::to_string(kMaxSoftBodyNodes) + " nodes and " +
              std::to_string(kMaxSoftBodyFaces) +
              " faces per soft body (what a viewer draws): simplify its mesh (" + soft.mesh + ")");
}

MeshMassProperties mass_properties(const TriangleMesh& mesh) {
  // Signed tetrahedra from the origin to each triangle: volume, first and second moments.
  double volume = 0.0;
  std::array<double, 3> first{};
  std::array<double, 6> second{};  // xx, yy, zz, xy, yz, zx integrals of the volume
  for (const auto& triangle : mesh.triangles) {
    const auto& a = mesh.vertices[triangle[0]];
    const auto& b = mesh.vertices[triangle[1]];
    const auto& c = mesh.vertices[triangle[2]];
    const double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                       a[2] * (b[0] * c[1] - b[1] * c[0]);
    const double v = det / 6.0;
    volume += v;
    for (int k = 0; k < 3; ++k) first[k] += v * (a[k] + b[k] + c[k]) / 4.0;
    // Integral of x_i x_j over a tetrahedron with one vertex at the origin.
    auto moment = [&](int i, int j) {
      return det / 120.0 *
             (2 * (a[i] * a[j] + b[i] * b[j] + c[i] * c[j]) + a[i] * b[j] + a[j] * b[i] +
              a[i] * c[j] + a[j] * c[i] + b[i] * c[j] + b[j] * c[i]);
    };
    second[0] += moment(0, 0);
    second[1] += moment(1, 1);
    second[2] += moment(2, 2);
    second[3] += moment(0, 1);
    second[4] += moment(1, 2);
    second[5] += moment(2, 0);
  }
  MeshMassProperties out;
  std::array<double, 3> low{1e300, 1e300, 1e300}, high{-1e300, -1e300, -1e300};
  for (const auto& p : mesh.vertices)
    for (int k = 0; k < 3; ++k) {
      low[k] = std::min(low[k], p[k]);
      high[k] = std::max(high[k], p[k]);
    }
  double box_volume = 1.0;
  for (int k = 0; k < 3; ++k) box_volume *= std::max(high[k] - low[k], 1e-9);
  if (std::abs(volume) < 1e-6 * box_volume) {
    // Not closed: a solid box over the vertices.
    out.from_bounding_box = true;
    out.volume_m3 = box_volume;
    std::array<double, 3> size{};
    for (int k = 0; k < 3; ++k) {
      out.centroid_m[k] = (low[k] + high[k]) / 2;
      size[k] = high[k] - low[k];
    }
    out.inertia_per_kg = {(size[1] * size[1] + size[2] * size[2]) / 12, 0, 0, 0,
                          (size[0] * size[0] + size[2] * size[2]) / 12, 0, 0, 0,
                          (size[0] * size[0] + size[1] * size[1]) / 12};
    return out;
  }
  // Inward-facing triangles give a negative volume; the ratios below do not mind.
  out.volume_m3 = std::abs(volume);
  for (int k = 0; k < 3; ++k) out.centroid_m[k] = first[k] / volume;
  // Second moments per unit mass about the centroid (parallel axis theorem).
  const auto& c = out.centroid_m;
  const double xx = second[0] / volume - c[0] * c[0];
  const double yy = second[1] / volume - c[1] * c[1];
  const double zz = second[2] / volume - c[2] * c[2];
  const double xy = second[3] / volume - c[0] * c[1];
  const double yz = second[4] / volume - c[1] * c[2];
  const double zx = second[5] / volume - c[2] * c[0];
  out.inertia_per_kg = {yy + zz, -xy, -zx, -xy, xx + zz, -yz, -zx, -yz, xx + yy};
  return out;
}

PrincipalInertia principal_inertia(const MeshMassProperties& mesh,
                                   const std::array<double, 3>& point, const Matrix3& frame) {
  using Matrix = Eigen::Matrix3d;
  const Matrix about_centroid =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(mesh.inertia_per_kg.data());
  // Parallel axis theorem, from the centroid to `point`.
  const Eigen::Vector3d d(point[0] - mesh.centroid_m[0], point[1] - mesh.centroid_m[1],
                          point[2] - mesh.centroid_m[2]);
  const Matrix about_point =
      about_centroid + (d.squaredNorm() * Matrix::Identity() - d * d.transpose());
  const Matrix rotation =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(frame.data());
  const Matrix in_frame = rotation.transpose() * about_point * rotation;
  const Eigen::SelfAdjointEigenSolver<Matrix> solver(in_frame);
  Matrix axes = solver.eigenvectors();
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);  // a rotation, not a reflection
  PrincipalInertia out;
  for (int k = 0; k < 3; ++k) out.moments_per_kg[k] = solver.eigenvalues()[k];
  for (int r = 0; r < 3; ++r)
    for (int col = 0; col < 3; ++col) out.axes[3 * r + col] = axes(r, col);
  return out;
}

}  // namespace afhub::physics
