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
  std::unique_ptr<btTriangleMesh> triangles;
  std::vector<btScalar> points;  // for a point cloud shape
};

// `com_from_mesh`: the mesh frame seen from the centre of mass (inverse of the
// inertial offset). `mesh` is the loaded collision mesh, when the body has one.
// A dynamic body cannot have a static triangle mesh: its TRIMESH collides as its convex hull.
CollisionShape build_collision_shape(const BodySpec& body, const btTransform& com_from_mesh,
                                     const TriangleMesh* mesh, bool dynamic);

}  // namespace afhub::physics
