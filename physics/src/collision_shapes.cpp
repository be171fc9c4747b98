// Collision shapes (see collision_shapes.hpp).
#include "collision_shapes.hpp"

#include <BulletCollision/CollisionShapes/btConvexPointCloudShape.h>
#include <LinearMath/btConvexHullComputer.h>

#include "frames.hpp"

namespace afhub::physics {
namespace {

btCollisionShape* primitive(const ShapeSpec& spec, CollisionShape& owner) {
  std::unique_ptr<btCollisionShape> shape;
  switch (spec.kind) {
    case ShapeKind::kBox:
      shape = std::make_unique<btBoxShape>(to_bt(spec.box_size_m) / 2);
      break;
    case ShapeKind::kSphere:
      shape = std::make_unique<btSphereShape>(spec.radius_m);
      break;
    case ShapeKind::kCylinder: {
      btVector3 half(spec.radius_m, spec.radius_m, spec.radius_m);
      half[spec.axis] = spec.height_m / 2;
      if (spec.axis == 0) shape = std::make_unique<btCylinderShapeX>(half);
      if (spec.axis == 1) shape = std::make_unique<btCylinderShape>(half);
      if (spec.axis == 2) shape = std::make_unique<btCylinderShapeZ>(half);
      break;
    }
    case ShapeKind::kCapsule:
      if (spec.axis == 0) shape = std::make_unique<btCapsuleShapeX>(spec.radius_m, spec.height_m);
      if (spec.axis == 1) shape = std::make_unique<btCapsuleShape>(spec.radius_m, spec.height_m);
      if (spec.axis == 2) shape = std::make_unique<btCapsuleShapeZ>(spec.radius_m, spec.height_m);
      break;
    case ShapeKind::kCone:
      if (spec.axis == 0) shape = std::make_unique<btConeShapeX>(spec.radius_m, spec.height_m);
      if (spec.axis == 1) shape = std::make_unique<btConeShape>(spec.radius_m, spec.height_m);
      if (spec.axis == 2) shape = std::make_unique<btConeShapeZ>(spec.radius_m, spec.height_m);
      break;
    case ShapeKind::kPlane:
      shape = std::make_unique<btStaticPlaneShape>(to_bt(spec.plane_normal).normalized(),
                                                   spec.plane_offset_m);
      break;
  }
  owner.shapes.push_back(std::move(shape));
  return owner.shapes.back().get();
}

// The hull's own vertices only (a mesh has many more): cheaper support queries.
std::unique_ptr<btCollisionShape> convex_hull(const std::vector<btVector3>& points) {
  btConvexHullComputer computer;
  computer.compute(points.data()->m_floats, sizeof(btVector3), static_cast<int>(points.size()), 0,
                   0);
  auto hull = std::make_unique<btConvexHullShape>();
  for (int i = 0; i < computer.vertices.size(); ++i) hull->addPoint(computer.vertices[i], false);
  hull->recalcLocalAabb();
  return hull;
}

btCollisionShape* add_mesh(const BodySpec& body, const btTransform& com_from_mesh,
                           const TriangleMesh& mesh, bool dynamic, CollisionShape& owner) {
  // Vertices move into the centre-of-mass frame, so no compound is needed for one mesh.
  std::vector<btVector3> points;
  points.reserve(mesh.vertices.size());
  for (const auto& v : mesh.vertices) points.push_back(com_from_mesh * btVector3(v[0], v[1], v[2]));
  std::unique_ptr<btCollisionShape> shape;
  auto triangles = [&] {
    auto& made = owner.triangles.emplace_back(std::make_unique<btTriangleMesh>(true, false));
    for (const auto& t : mesh.triangles)
      made->addTriangle(points[t[0]], points[t[1]], points[t[2]], true);
    return made.get();
  };
  switch (body.collision_mesh_type) {
    case CollisionMeshType::kConvexHull:
      shape = convex_hull(points);
      break;
    case CollisionMeshType::kConvexMesh:
      shape = std::make_unique<btConvexTriangleMeshShape>(triangles());
      break;
    case CollisionMeshType::kPointCloud: {
      std::vector<btScalar>& cloud = owner.point_clouds.emplace_back();
      cloud.reserve(points.size() * 4);
      for (const auto& p : points)
        for (int k = 0; k < 4; ++k) cloud.push_back(k < 3 ? p[k] : 0);
      shape = std::make_unique<btConvexPointCloudShape>(reinterpret_cast<btVector3*>(cloud.data()),
                                                        static_cast<int>(points.size()),
                                                        btVector3(1, 1, 1));
      break;
    }
    case CollisionMeshType::kTrimesh:
      // A moving triangle mesh collides as its convex hull, as in MuJoCo: Bullet's
      // GImpact (AMBF's choice) allocates on every contact step and is far slower.
      if (dynamic)
        shape = convex_hull(points);
      else
        shape = std::make_unique<btBvhTriangleMeshShape>(triangles(), true);
      break;
  }
  shape->setMargin(body.collision_margin);
  owner.shapes.push_back(std::move(shape));
  return owner.shapes.back().get();
}

}  // namespace

CollisionShape build_collision_shape(const BodySpec& body, const btTransform& com_from_mesh,
                                     const TriangleMesh* mesh,
                                     const std::vector<const TriangleMesh*>& parts, bool dynamic) {
  CollisionShape owner;
  if (mesh && parts.empty() && body.collision_shapes.empty()) {
    owner.root = add_mesh(body, com_from_mesh, *mesh, dynamic, owner);
    return owner;
  }
  if (!mesh && parts.empty() && body.collision_shapes.empty()) {
    owner.shapes.push_back(std::make_unique<btEmptyShape>());
    owner.root = owner.shapes.back().get();
    return owner;
  }
  auto compound = std::make_unique<btCompoundShape>();
  // Each mesh's vertices are already in the centre-of-mass frame.
  if (mesh)
    compound->addChildShape(btTransform::getIdentity(),
                            add_mesh(body, com_from_mesh, *mesh, dynamic, owner));
  for (std::size_t p = 0; p < parts.size(); ++p)
    compound->addChildShape(
        btTransform::getIdentity(),
        add_mesh(body, com_from_mesh * to_transform(body.collision_mesh_parts[p].offset), *parts[p],
                 dynamic, owner));
  for (const ShapeSpec& spec : body.collision_shapes) {
    btCollisionShape* child = primitive(spec, owner);
    child->setMargin(body.collision_margin);
    compound->addChildShape(com_from_mesh * to_transform(spec.offset), child);
  }
  // A single plane cannot sit in a compound (it is concave): use it directly.
  if (compound->getNumChildShapes() == 1 && !body.collision_shapes.empty() &&
      body.collision_shapes[0].kind == ShapeKind::kPlane) {
    owner.root = owner.shapes.back().get();
    return owner;
  }
  owner.shapes.push_back(std::move(compound));
  owner.root = owner.shapes.back().get();
  return owner;
}

}  // namespace afhub::physics
