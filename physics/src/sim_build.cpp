// Build: the Bullet objects, made once from the Model. Rigid bodies at `location` x
// `inertial offset` with their collision shapes and inertia, joints, soft bodies
// with their config, sensor rays grouped by body, constraint actuators, and the
// world file's lights and cameras (their frames, on their parent bodies).
#include <BulletSoftBody/btSoftBodyHelpers.h>

#include <map>

#include "afhub/shm_layout/error.hpp"
#include "body_groups.hpp"
#include "simulation_data.hpp"

namespace afhub::physics {
namespace {

// Bullet's btSoftBody::Config and Material fields by their ADF names.
void configure_soft_body(btSoftBody& soft, const SoftBodySpec& spec) {
  btSoftBody::Config& c = soft.m_cfg;
  btSoftBody::Material& m = *soft.m_materials[0];
  const std::map<std::string, btScalar*> fields = {{"kVCF", &c.kVCF},
                                                   {"kDP", &c.kDP},
                                                   {"kDG", &c.kDG},
                                                   {"kLF", &c.kLF},
                                                   {"kPR", &c.kPR},
                                                   {"kVC", &c.kVC},
                                                   {"kDF", &c.kDF},
                                                   {"kMT", &c.kMT},
                                                   {"kCHR", &c.kCHR},
                                                   {"kKHR", &c.kKHR},
                                                   {"kSHR", &c.kSHR},
                                                   {"kAHR", &c.kAHR},
                                                   {"kSRHR_CL", &c.kSRHR_CL},
                                                   {"kSKHR_CL", &c.kSKHR_CL},
                                                   {"kSSHR_CL", &c.kSSHR_CL},
                                                   {"kSR_SPLT_CL", &c.kSR_SPLT_CL},
                                                   {"kSK_SPLT_CL", &c.kSK_SPLT_CL},
                                                   {"kSS_SPLT_CL", &c.kSS_SPLT_CL},
                                                   {"maxvolume", &c.maxvolume},
                                                   {"timescale", &c.timescale},
                                                   {"kLST", &m.m_kLST},
                                                   {"kAST", &m.m_kAST},
                                                   {"kVST", &m.m_kVST}};
  const std::map<std::string, int*> iterations = {{"viterations", &c.viterations},
                                                  {"piterations", &c.piterations},
                                                  {"diterations", &c.diterations},
                                                  {"citerations", &c.citerations}};
  for (const auto& [key, value] : spec.config) {
    if (auto field = fields.find(key); field != fields.end()) *field->second = value;
    if (auto count = iterations.find(key); count != iterations.end())
      *count->second = static_cast<int>(value);
  }
  if (spec.bending_constraint > 0) soft.generateBendingConstraints(spec.bending_constraint, &m);
  if (spec.clusters > 0) soft.generateClusters(spec.clusters);
}

// A light or camera looking along `direction` (its x axis) with `up` as its z axis.
btQuaternion look_rotation(const Vec3& direction, const Vec3& up) {
  btVector3 x = to_bt(direction);
  x = x.length2() > 1e-24 ? x.normalized() : btVector3(1, 0, 0);
  btVector3 y = to_bt(up).cross(x);
  if (y.length2() < 1e-12) y = btVector3(0, 1, 0).cross(x);
  y.normalize();
  const btVector3 z = x.cross(y);
  btQuaternion rotation;
  btMatrix3x3(x.x(), y.x(), z.x(), x.y(), y.y(), z.y(), x.z(), y.z(), z.z()).getRotation(rotation);
  return rotation;
}

}  // namespace

void Simulation::Data::build_bodies() {
  // Every collision mesh read at once (one reader process), each (file, scale) once.
  std::map<MeshKey, std::size_t> mesh_index;
  std::vector<MeshRequest> requests;
  auto request = [&](const BodySpec& spec, const std::string& path, const Vec3& scale) {
    if (mesh_index.emplace(mesh_key(path, scale), requests.size()).second)
      requests.push_back({path, scale, spec.where, "body '" + spec.identifier + "'"});
  };
  for (const BodySpec& spec : model.bodies) {
    if (!spec.collision_mesh.empty()) request(spec, spec.collision_mesh, uniform_scale(spec.scale));
    for (const PlacedMesh& part : spec.collision_mesh_parts) request(spec, part.path, part.scale);
  }
  const std::vector<TriangleMesh> meshes = load_body_meshes(requests);
  bodies.resize(model.bodies.size());
  for (std::size_t c = 0; c < chain_plans.size(); ++c)
    for (std::size_t l = 0; l < chain_plans[c].joints.size(); ++l) {
      BodyData& link = bodies[model.joints[chain_plans[c].joints[l]].child];
      link.chain = static_cast<int>(c);
      link.link = static_cast<int>(l);
    }
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const BodySpec& spec = model.bodies[i];
    BodyData& body = bodies[i];
    const TriangleMesh* mesh =
        spec.collision_mesh.empty()
            ? nullptr
            : &meshes[mesh_index.at(mesh_key(spec.collision_mesh, uniform_scale(spec.scale)))];
    body.dynamic = spec.mass_kg > 0.0;
    Placement inertial = spec.inertial_offset.value_or(Placement{});
    std::optional<MeshMassProperties> properties;
    if (mesh && (!spec.inertial_offset || !spec.inertia_kgm2)) properties = mass_properties(*mesh);
    if (!spec.inertial_offset && properties) {
      const auto& c = properties->centroid_m;
      inertial.position_m = {c[0], c[1], c[2]};
    }
    btTransform mesh_from_com = to_transform(inertial);
    // Inertia from the mesh: its full tensor about its centroid, seen in the inertial
    // frame and diagonalised; the inertial frame turns to the principal axes.
    std::optional<PrincipalInertia> principal;
    if (body.dynamic && !spec.inertia_kgm2 && properties) {
      const btMatrix3x3 turn = mesh_from_com.getBasis();
      Matrix3 frame{};
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) frame[3 * r + c] = turn[r][c];
      principal = principal_inertia(*properties, properties->centroid_m, frame);
      const Matrix3& a = principal->axes;
      mesh_from_com.setBasis(turn *
                             btMatrix3x3(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8]));
    }
    body.com_from_mesh = mesh_from_com.inverse();
    std::vector<const TriangleMesh*> parts;
    for (const PlacedMesh& part : spec.collision_mesh_parts)
      parts.push_back(&meshes[mesh_index.at(mesh_key(part.path, part.scale))]);
    body.shape = build_collision_shape(spec, body.com_from_mesh, mesh, parts, body.dynamic);
    btVector3 inertia(0, 0, 0);
    if (body.dynamic) {
      if (spec.inertia_kgm2) {
        inertia = to_bt(*spec.inertia_kgm2);
      } else if (principal) {
        const auto& unit = principal->moments_per_kg;
        inertia = btVector3(unit[0], unit[1], unit[2]) * spec.mass_kg;
      } else if (!spec.collision_shapes.empty()) {
        body.shape.root->calculateLocalInertia(spec.mass_kg, inertia);
      } else {
        // No geometry at all: a small solid sphere of 5 cm radius.
        inertia = btVector3(1, 1, 1) * (0.4 * spec.mass_kg * 0.05 * 0.05);
      }
    }
    btRigidBody::btRigidBodyConstructionInfo info(spec.mass_kg, nullptr, body.shape.root, inertia);
    body.initial_com = to_transform(spec.location) * mesh_from_com;
    info.m_startWorldTransform = body.initial_com;
    info.m_friction = spec.static_friction;
    info.m_rollingFriction = spec.rolling_friction;
    info.m_restitution = spec.restitution;
    info.m_linearDamping = spec.linear_damping;
    info.m_angularDamping = spec.angular_damping;
    body.body = std::make_unique<btRigidBody>(info);
    body.body->setUserIndex(static_cast<int>(i));
    body.body->setActivationState(DISABLE_DEACTIVATION);  // controllers expect live bodies
    if (spec.gravity_mps2) body.body->setFlags(body.body->getFlags() | BT_DISABLE_WORLD_GRAVITY);
    if (body.chain < 0) world.addRigidBody(body.body.get());  // a link's is its mirror
    if (spec.gravity_mps2) body.body->setGravity(to_bt(*spec.gravity_mps2));
  }
}

void Simulation::Data::build_joints() {
  for (const JointSpec& spec : model.joints) {
    BodyData& parent = bodies[spec.parent];
    BodyData& child = bodies[spec.child];
    joints.push_back(std::make_unique<JointModel>(spec, *parent.body, *child.body,
                                                  parent.com_from_mesh, child.com_from_mesh, dt_s,
                                                  child.chain >= 0));
    if (btTypedConstraint* constraint = joints.back()->constraint())
      world.addConstraint(constraint, spec.ignore_inter_collision);
  }
  raise_gain_caps();
  build_chains();
  part_overlaps();  // among chains' links too
  mark_joint_islands();
}

// Every joint that moves a body is marked for the direct solve
// (constraint_solver.hpp), which then takes the whole Bullet island it is in
// (contacts join islands too), every island solved on its own, not batched. The
// moving bodies joined by joints (a static body joins nothing: it is the ground)
// hold a closed loop when they have as many joints as bodies, one more when some of
// them reach the ground: their joints are marked as in a loop, where the solve looks
// for the rows a loop repeats. A loop closed while running (an actuator's hold) is
// not marked, and makes the solve look too.
void Simulation::Data::mark_joint_islands() {
  if (!model.world.direct_solve) return;
  BodyGroups joined(bodies.size());
  // A chain's joints are coordinates, not constraints (sim_chains.cpp): not solved here.
  auto solved = [&](std::size_t j) {
    const JointSpec& spec = model.joints[j];
    return joints[j]->constraint() && (bodies[spec.parent].dynamic || bodies[spec.child].dynamic);
  };
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const JointSpec& spec = model.joints[j];
    if (solved(j) && bodies[spec.parent].dynamic && bodies[spec.child].dynamic)
      joined.join(spec.parent, spec.child);
  }
  struct Island {
    int bodies = 0, joints = 0;
    bool grounded = false;
  };
  std::vector<Island> islands(bodies.size());
  for (std::size_t b = 0; b < bodies.size(); ++b)
    if (bodies[b].dynamic && bodies[b].chain < 0)
      ++islands[joined.root(static_cast<int>(b))].bodies;
  auto island_of = [&](const JointSpec& spec) {
    return joined.root(bodies[spec.parent].dynamic ? spec.parent : spec.child);
  };
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    if (!solved(j)) continue;
    const JointSpec& spec = model.joints[j];
    Island& island = islands[island_of(spec)];
    ++island.joints;
    island.grounded |= !bodies[spec.parent].dynamic || !bodies[spec.child].dynamic;
  }
  bool any = false;
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    if (!solved(j)) continue;
    const Island& island = islands[island_of(model.joints[j])];
    const bool loop = island.joints >= island.bodies + (island.grounded ? 1 : 0);
    joints[j]->constraint()->setUserConstraintType(loop ? ConstraintSolver::kInLoopIsland
                                                        : ConstraintSolver::kInTreeIsland);
    any = true;
  }
  if (any) {
    solver.enable_direct_solve();
    world.getSolverInfo().m_minimumSolverBatchSize = 1;
  }
  // Groups of moving bodies joined by joints, and chains: islands, unless contacts
  // join them.
  const auto groups = std::count_if(islands.begin(), islands.end(),
                                    [](const Island& island) { return island.bodies > 0; }) +
                      static_cast<std::ptrdiff_t>(chains.size());
  if ((any || !chains.empty()) && model.world.solver_threads > 1 &&
      groups >= ParallelIslands::kMinItems)
    world.solve_islands_in_parallel(
        static_cast<int>(model.bodies.size()),
        static_cast<int>(model.joints.size() + model.actuators.size()),
        static_cast<int>(model.bodies.size() + model.soft_bodies.size()));
}

void Simulation::Data::build_soft_bodies() {
  for (const SoftBodySpec& spec : model.soft_bodies) {
    const TriangleMesh mesh =
        load_body_mesh(spec.mesh, spec.scale, spec.where, "soft body '" + spec.identifier + "'");
    check_soft_body_mesh(spec, mesh);
    const btTransform place = to_transform(spec.location);
    std::vector<btScalar> vertices;
    for (const auto& v : mesh.vertices) {
      const btVector3 p = place * btVector3(v[0], v[1], v[2]);
      vertices.insert(vertices.end(), {p.x(), p.y(), p.z()});
    }
    std::vector<int> triangles;
    for (const auto& t : mesh.triangles)
      triangles.insert(triangles.end(),
                       {static_cast<int>(t[0]), static_cast<int>(t[1]), static_cast<int>(t[2])});
    btSoftBody* soft = btSoftBodyHelpers::CreateFromTriMesh(
        world.getWorldInfo(), vertices.data(), triangles.data(),
        static_cast<int>(mesh.triangles.size()), false);
    configure_soft_body(*soft, spec);
    soft->setTotalMass(spec.mass_kg);
    for (int node : spec.fixed_nodes) {
      if (node >= soft->m_nodes.size())
        throw Error(spec.where.str() + ": error: fixed node " + std::to_string(node) +
                    " does not exist; the mesh has " + std::to_string(soft->m_nodes.size()) +
                    " nodes (0 to " + std::to_string(soft->m_nodes.size() - 1) + ")");
      soft->setMass(node, 0);
    }
    soft->setUserIndex(-1);
    soft->setActivationState(DISABLE_DEACTIVATION);
    world.addSoftBody(soft);
    SoftBodyData data;
    data.body = soft;
    for (int n = 0; n < soft->m_nodes.size(); ++n)
      data.initial_positions.push_back(soft->m_nodes[n].m_x);
    data.good_positions = data.initial_positions;
    soft_bodies.push_back(std::move(data));
  }
}

void Simulation::Data::build_sensors() {
  // Rays grouped by parent body, in file order, so that each body reads a contiguous run.
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    bodies[b].first_ray = rays.size();
    for (const SensorSpec& sensor : model.sensors) {
      if (sensor.parent != static_cast<int>(b)) continue;
      const btTransform place = to_transform(sensor.location);
      for (const auto& [offset, direction] : sensor.rays) {
        Ray ray;
        ray.parent = static_cast<int>(b);
        ray.from_in_mesh = place * to_bt(offset);
        ray.to_in_mesh = place * (to_bt(offset) + to_bt(direction).normalized() * sensor.range_m);
        ray.range_m = sensor.range_m;
        rays.push_back(ray);
      }
    }
    bodies[b].ray_count = rays.size() - bodies[b].first_ray;
  }
}

void Simulation::Data::build_actuators() {
  world.reserve_constraints(static_cast<int>(model.joints.size() + model.actuators.size()));
  for (std::size_t a = 0; a < model.actuators.size(); ++a) {
    const ActuatorSpec& spec = model.actuators[a];
    ActuatorData actuator;
    actuator.parent = spec.parent;
    actuator.point_in_mesh = to_bt(spec.location.position_m);
    actuator.storage = std::make_unique<std::optional<btPoint2PointConstraint>>();
    actuators.push_back(std::move(actuator));
    bodies[spec.parent].actuators.push_back(static_cast<int>(a));
  }
  // An engaged actuator adds a constraint reference to both bodies (and an entry to
  // their lists of bodies not to collide with): Bullet grows those arrays on first
  // use. Adding and removing as many references as there are actuators, here, leaves
  // room for them on every body a constraint may hold.
  if (actuators.empty()) return;
  std::vector<std::unique_ptr<btPoint2PointConstraint>> room;
  for (BodyData& body : bodies) {
    if (!(body.body->getInvMass() > 0) && body.actuators.empty()) continue;
    room.clear();
    for (std::size_t a = 0; a < actuators.size(); ++a)
      room.push_back(std::make_unique<btPoint2PointConstraint>(*body.body, btVector3(0, 0, 0)));
    for (auto& constraint : room) body.body->addConstraintRef(constraint.get());
    for (auto& constraint : room) body.body->removeConstraintRef(constraint.get());
  }
}

void Simulation::Data::build_world_objects() {
  auto build = [&](const std::vector<WorldObjectSpec>& specs, std::vector<WorldObjectData>& out) {
    for (const WorldObjectSpec& spec : specs)
      out.push_back({world_object_parent(model, spec),
                     btTransform(look_rotation(spec.direction, spec.up), to_bt(spec.position_m))});
  };
  build(model.world.lights, lights);
  build(model.world.cameras, cameras);
}

}  // namespace afhub::physics
