// Boxes for bodies whose collision mesh cannot be used (see mesh_fallback.hpp).
#include "afhub/physics/mesh_fallback.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "afhub/physics/mesh.hpp"

namespace afhub::physics {
namespace {

constexpr double kCubeM = 0.1;      // when the block gives no inertia to match
constexpr double kMinSideM = 1e-3;  // an inertia no solid box has: its thin sides

std::string metres(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}

// A box of mass m has I_x = m (y^2 + z^2) / 12, and so on: y^2 + z^2 = 12 I_x / m.
ShapeSpec box_for(const BodySpec& body, std::string& made_from) {
  ShapeSpec box;
  box.kind = ShapeKind::kBox;
  box.offset = body.inertial_offset.value_or(Placement{});
  if (body.mass_kg > 0.0 && body.inertia_kgm2) {
    const Vec3& i = *body.inertia_kgm2;
    const double k = 6.0 / body.mass_kg;
    auto side = [&](double a, double b, double c) {
      return std::max(kMinSideM, std::sqrt(std::max(0.0, k * (b + c - a))));
    };
    box.box_size_m = {side(i.x, i.y, i.z), side(i.y, i.z, i.x), side(i.z, i.x, i.y)};
    made_from = "with its mass and inertia";
  } else {
    box.box_size_m = {kCubeM, kCubeM, kCubeM};
    made_from = body.mass_kg > 0.0 ? "(its block gives no inertia to match)"
                                   : "(a static body: its block gives no inertia to match)";
  }
  return box;
}

}  // namespace

std::vector<std::string> fall_back_to_boxes(Model& model) {
  std::vector<MeshRequest> requests;
  std::vector<std::size_t> owners;
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const BodySpec& body = model.bodies[b];
    const std::string owner = "body '" + body.identifier + "'";
    if (!body.collision_mesh.empty()) {
      requests.push_back({body.collision_mesh, uniform_scale(body.scale), body.where, owner});
      owners.push_back(b);
    }
    for (const PlacedMesh& part : body.collision_mesh_parts) {
      requests.push_back({part.path, part.scale, body.where, owner});
      owners.push_back(b);
    }
  }
  const std::vector<MeshOrError> read = try_load_body_meshes(requests);
  std::vector<std::string> warnings;
  for (std::size_t r = 0; r < requests.size(); ++r) {
    BodySpec& body = model.bodies[owners[r]];
    // A body whose first unusable mesh this is: all its meshes give way to the box.
    if (read[r].mesh || (body.collision_mesh.empty() && body.collision_mesh_parts.empty()))
      continue;
    std::string made_from;
    const ShapeSpec box = box_for(body, made_from);
    const Vec3& size = box.box_size_m;
    warnings.push_back(body.where.str() + ": warning: body '" + body.identifier +
                       "': its mesh cannot be used (" + read[r].error + "): it collides as a box " +
                       metres(size.x) + " x " + metres(size.y) + " x " + metres(size.z) + " m " +
                       made_from + " (--mesh-fallback box)");
    body.collision_mesh.clear();
    body.collision_mesh_parts.clear();
    body.collision_shapes.push_back(box);
  }
  return warnings;
}

}  // namespace afhub::physics
