// Mesh reading (assimp) and mass properties (see mesh.hpp).
#include "afhub/physics/mesh.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>

#include <set>

#include "afhub/shm_layout/error.hpp"
#include "afhub/yaml/input_file.hpp"

namespace afhub::physics {
namespace {

// A vertex farther than this from its mesh's origin is garbage, not a part.
constexpr double kMaxVertexM = 1e5;

// Runs `load` and prefixes its error with the block that names the mesh.
template <class Load>
auto for_block(const SourceLocation& where, const std::string& owner, Load load) {
  try {
    return load();
  } catch (const Error& error) {
    throw Error(where.str() + ": error: " + owner + ": its mesh cannot be used: " + error.what());
  }
}

}  // namespace

TriangleMesh load_mesh(const std::string& path, double scale) {
  yaml::check_input_file(path, kMaxMeshFileBytes, "a mesh (STL, OBJ, DAE, ...)");
  Assimp::Importer importer;
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                  aiProcess_PreTransformVertices);
  if (!scene || !scene->mRootNode)
    throw Error(path + ": error: cannot read this mesh: " + importer.GetErrorString());
  TriangleMesh mesh;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* part = scene->mMeshes[m];
    const auto base = static_cast<unsigned>(mesh.vertices.size());
    if (mesh.vertices.size() + part->mNumVertices > kMaxMeshVertices ||
        mesh.triangles.size() + part->mNumFaces > kMaxMeshTriangles)
      throw Error(path + ": error: the mesh has more than " + std::to_string(kMaxMeshTriangles) +
                  " triangles or " + std::to_string(kMaxMeshVertices) +
                  " vertices; simplify it (a collision mesh needs far fewer)");
    for (unsigned v = 0; v < part->mNumVertices; ++v) {
      const aiVector3D& p = part->mVertices[v];
      const std::array<double, 3> scaled{p.x * scale, p.y * scale, p.z * scale};
      for (double component : scaled)
        if (!std::isfinite(component) || std::abs(component) > kMaxVertexM)
          throw Error(path + ": error: vertex " + std::to_string(mesh.vertices.size()) + " is (" +
                      std::to_string(p.x) + ", " + std::to_string(p.y) + ", " +
                      std::to_string(p.z) +
                      "): not a finite point within 100 km of the origin; repair the mesh");
      mesh.vertices.push_back(scaled);
    }
    for (unsigned f = 0; f < part->mNumFaces; ++f) {
      const aiFace& face = part->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines have no volume
      for (unsigned k = 0; k < 3; ++k)
        if (face.mIndices[k] >= part->mNumVertices)
          throw Error(path + ": error: face " + std::to_string(f) + " names a vertex beyond the " +
                      std::to_string(part->mNumVertices) + " of its part; repair the mesh");
      mesh.triangles.push_back(
          {base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
    }
  }
  if (mesh.triangles.empty())
    throw Error(path + ": error: the mesh has no triangles; export it with faces");
  return mesh;
}

TriangleMesh load_body_mesh(const std::string& path, double scale, const SourceLocation& where,
                            const std::string& owner) {
  return for_block(where, owner, [&] { return load_mesh(path, scale); });
}

std::size_t check_meshes(const Model& model) {
  std::set<std::pair<std::string, double>> read;
  auto load = [&](const std::string& path, double scale, const SourceLocation& where,
                  const std::string& owner) {
    if (path.empty() || !read.emplace(path, scale).second) return;
    load_body_mesh(path, scale, where, owner);
  };
  for (const BodySpec& body : model.bodies) {
    load(body.collision_mesh, body.scale, body.where, "body '" + body.identifier + "'");
    load(body.visual_mesh, body.scale, body.where, "body '" + body.identifier + "' (visual)");
  }
  for (const SoftBodySpec& soft : model.soft_bodies)
    load(soft.mesh, soft.scale, soft.where, "soft body '" + soft.identifier + "'");
  return read.size();
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
