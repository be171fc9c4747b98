// A body's collision shape from its spec: primitives, compounds or a mesh of the
// requested type, expressed in the body's centre-of-mass frame.
#pragma once

#include <btBulletDynamicsCommon.h>

#include <memory>
#include <vector>

#include "afhub/physics/mesh.hpp"
#include "afhub/physics/model.hpp"

namespace afhub::physics {

// Owns the shape and whatever it points into (child shapes, triangle arrays).
struct CollisionShape {
  btCollisionShape* root = nullptr;
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btTriangleMesh>> triangles;
  std::vector<std::vector<btScalar>> point_clouds;  // for point cloud shapes
};

// `com_from_mesh`: the mesh frame seen from the centre of mass (inverse of the
// inertial offset). `mesh` is the loaded collision mesh, when the body has one, and
// `parts` its loaded `collision_mesh_parts`, in order.
// A dynamic body cannot have a static triangle mesh: its TRIMESH collides as its convex hull.
CollisionShape build_collision_shape(const BodySpec& body, const btTransform& com_from_mesh,
                                     const TriangleMesh* mesh,
                                     const std::vector<const TriangleMesh*>& parts, bool dynamic);

}  // namespace afhub::physics
