// The Bullet world (see simulation.hpp): bodies at `location` x `inertial offset`,
// collision filtering by file and group, joints, soft bodies and proximity sensors;
// Cartesian and joint commands applied before each fixed step.
#include "afhub/physics/simulation.hpp"

#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "afhub/shm_layout/error.hpp"
#include "collision_shapes.hpp"
#include "frames.hpp"
#include "joint_model.hpp"

namespace afhub::physics {
namespace {

bool finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
bool finite(const btVector3& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

Pose to_pose(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  return {from_bt(t.getOrigin()), {q.x(), q.y(), q.z(), q.w()}};
}

btTransform from_pose(const Pose& pose) {
  const Quaternion& q = pose.orientation;
  btQuaternion rotation(q.x, q.y, q.z, q.w);
  if (rotation.length2() < 1e-12) rotation = btQuaternion::getIdentity();
  return btTransform(rotation.normalized(), to_bt(pose.position_m));
}

// A rigid body and its current Cartesian command.
struct BodyData {
  CollisionShape shape;
  std::unique_ptr<btRigidBody> body;
  btTransform com_from_mesh;  // the mesh frame seen from the centre of mass
  btTransform initial_com;
  bool dynamic = false;
  bool commanded = false;
  CartesianCommandType type = CartesianCommandType::kForce;
  btTransform target;
  btVector3 force{0, 0, 0}, torque{0, 0, 0}, linear_velocity{0, 0, 0}, angular_velocity{0, 0, 0};
  btVector3 linear_integral{0, 0, 0}, angular_integral{0, 0, 0};
  btVector3 previous_linear_error{0, 0, 0}, previous_angular_error{0, 0, 0};
  bool has_previous_error = false;
  Wrench applied;
  std::vector<int> commanded_joints;         // joints whose current command came from this body
  std::size_t first_ray = 0, ray_count = 0;  // into Data::rays
  std::vector<int> actuators;                // into Data::actuators, file order
};

struct SoftBodyData {
  btSoftBody* body = nullptr;  // owned by the world
  std::vector<btVector3> initial_positions;
};

// A constraint actuator: a point-to-point constraint to whatever body touches it,
// made when commanded and removed when released.
struct ActuatorData {
  int parent = -1;
  btVector3 point_in_mesh;  // in the parent's mesh frame
  std::unique_ptr<btPoint2PointConstraint> hold;
};

// The first dynamic rigid body, other than `parent`, touching the probe sphere.
struct TouchingBody : btCollisionWorld::ContactResultCallback {
  explicit TouchingBody(const btCollisionObject* parent) : parent_(parent) {}
  btScalar addSingleResult(btManifoldPoint&, const btCollisionObjectWrapper* a, int, int,
                           const btCollisionObjectWrapper* b, int, int) override {
    for (const btCollisionObjectWrapper* side : {a, b}) {
      const btCollisionObject* object = side->getCollisionObject();
      const btRigidBody* body = btRigidBody::upcast(object);
      if (!found && body && object != parent_ && object->getUserIndex() >= 0 &&
          body->getInvMass() > 0)
        found = const_cast<btRigidBody*>(body);
    }
    return 0;
  }
  const btCollisionObject* parent_;
  btRigidBody* found = nullptr;
};

struct Ray {
  int parent = -1;
  btVector3 from_in_mesh, to_in_mesh;  // in the parent's mesh frame
  double range_m = 0.0;
  double distance_m = -1.0;  // the last reading
};

// Rigid bodies carry their index in user index 1; soft bodies carry -1.
class CollisionFilter : public btOverlapFilterCallback {
 public:
  explicit CollisionFilter(const Model& model) : model_(model) {}
  bool needBroadphaseCollision(btBroadphaseProxy* a, btBroadphaseProxy* b) const override {
    if (!(a->m_collisionFilterGroup & b->m_collisionFilterMask) ||
        !(b->m_collisionFilterGroup & a->m_collisionFilterMask))
      return false;
    const int i = static_cast<const btCollisionObject*>(a->m_clientObject)->getUserIndex();
    const int j = static_cast<const btCollisionObject*>(b->m_clientObject)->getUserIndex();
    if (i < 0 || j < 0) return true;
    const BodySpec& x = model_.bodies[i];
    const BodySpec& y = model_.bodies[j];
    if (x.file_index == y.file_index && model_.file_ignores_inter_collision[x.file_index])
      return false;
    // Bodies that name groups collide only with bodies sharing one.
    if (x.collision_groups.empty() || y.collision_groups.empty()) return true;
    for (int group : x.collision_groups)
      if (std::find(y.collision_groups.begin(), y.collision_groups.end(), group) !=
          y.collision_groups.end())
        return true;
    return false;
  }

 private:
  const Model& model_;
};

// Closest hit, ignoring the body the sensor sits on.
struct SensorRayCallback : btCollisionWorld::ClosestRayResultCallback {
  SensorRayCallback(const btVector3& from, const btVector3& to, const btCollisionObject* ignore)
      : ClosestRayResultCallback(from, to), ignore_(ignore) {}
  bool needsCollision(btBroadphaseProxy* proxy) const override {
    return proxy->m_clientObject != ignore_ && ClosestRayResultCallback::needsCollision(proxy);
  }
  const btCollisionObject* ignore_;
};

// Bullet's solver grows its work arrays when a scene gets more contacts or active
// joint limits than before: a heap allocation in the middle of a run. Reserving
// room up front keeps the step allocation-free for any scene that fits.
class PreallocatedSolver : public btSequentialImpulseConstraintSolver {
 public:
  PreallocatedSolver(int bodies, int joints) {
    constexpr int kContacts = 4096;  // contact points, each with two friction rows
    const int joint_rows = 6 * joints + 64;
    m_tmpSolverBodyPool.reserve(bodies + 64);
    m_tmpSolverContactConstraintPool.reserve(kContacts);
    m_tmpSolverContactFrictionConstraintPool.reserve(2 * kContacts);
    m_tmpSolverContactRollingFrictionConstraintPool.reserve(3 * kContacts);
    m_tmpSolverNonContactConstraintPool.reserve(joint_rows);
    m_orderTmpConstraintPool.reserve(kContacts);
    m_orderFrictionConstraintPool.reserve(2 * kContacts);
    m_orderNonContactConstraintPool.reserve(joint_rows);
    m_tmpConstraintSizesPool.reserve(joints + 64);
  }
};

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

}  // namespace

struct Simulation::Data {
  const Model& model;
  double dt_s;
  std::uint64_t steps = 0;

  btSoftBodyRigidBodyCollisionConfiguration collision_config;
  btCollisionDispatcher dispatcher{&collision_config};
  btDbvtBroadphase broadphase;
  PreallocatedSolver solver;
  btSoftRigidDynamicsWorld world{&dispatcher, &broadphase, &solver, &collision_config};
  CollisionFilter filter;

  std::vector<BodyData> bodies;
  std::vector<std::unique_ptr<JointModel>> joints;
  std::vector<SoftBodyData> soft_bodies;
  std::vector<Ray> rays;
  std::vector<ActuatorData> actuators;
  btSphereShape probe_shape{0.01};  // what an actuator feels for: 1 cm around its point
  btCollisionObject probe;

  Data(const Model& m, double dt)
      : model(m),
        dt_s(dt),
        solver(static_cast<int>(m.bodies.size()), static_cast<int>(m.joints.size())),
        filter(m) {}
  ~Data() {
    for (auto& joint : joints) world.removeConstraint(&joint->constraint());
    for (auto& actuator : actuators)
      if (actuator.hold) world.removeConstraint(actuator.hold.get());
    for (auto& body : bodies) world.removeRigidBody(body.body.get());
    for (auto& soft : soft_bodies) {
      world.removeSoftBody(soft.body);
      delete soft.body;
    }
  }

  void build_bodies();
  void build_joints();
  void build_soft_bodies();
  void build_sensors();
  void build_actuators();
  void actuate(ActuatorData& actuator, bool engage) noexcept;
  void apply_cartesian(BodyData& body) noexcept;
  void read_sensors() noexcept;
};

void Simulation::Data::build_bodies() {
  std::map<std::string, TriangleMesh> meshes;  // each file read once
  auto mesh_of = [&](const BodySpec& spec) -> const TriangleMesh* {
    const std::string& path = spec.collision_mesh;
    if (path.empty()) return nullptr;
    const std::string key = path + "@" + std::to_string(spec.scale);
    auto found = meshes.find(key);
    if (found == meshes.end()) found = meshes.emplace(key, load_mesh(path, spec.scale)).first;
    return &found->second;
  };
  bodies.resize(model.bodies.size());
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const BodySpec& spec = model.bodies[i];
    BodyData& body = bodies[i];
    body.commanded_joints.reserve(model.descendant_joints[i].size());  // no allocation in a run
    const TriangleMesh* mesh = mesh_of(spec);
    body.dynamic = spec.mass_kg > 0.0;
    Placement inertial = spec.inertial_offset.value_or(Placement{});
    std::optional<MeshMassProperties> properties;
    if (mesh && (!spec.inertial_offset || !spec.inertia_kgm2)) properties = mass_properties(*mesh);
    if (!spec.inertial_offset && properties) {
      const auto& c = properties->centroid_m;
      inertial.position_m = {c[0], c[1], c[2]};
    }
    const btTransform mesh_from_com = to_transform(inertial);
    body.com_from_mesh = mesh_from_com.inverse();
    body.shape = build_collision_shape(spec, body.com_from_mesh, mesh, body.dynamic);
    btVector3 inertia(0, 0, 0);
    if (body.dynamic) {
      if (spec.inertia_kgm2) {
        inertia = to_bt(*spec.inertia_kgm2);
      } else if (properties) {
        const auto& unit = properties->inertia_per_kg;
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
    world.addRigidBody(body.body.get());
    if (spec.gravity_mps2) body.body->setGravity(to_bt(*spec.gravity_mps2));
  }
}

void Simulation::Data::build_joints() {
  for (const JointSpec& spec : model.joints) {
    BodyData& parent = bodies[spec.parent];
    BodyData& child = bodies[spec.child];
    joints.push_back(std::make_unique<JointModel>(spec, *parent.body, *child.body,
                                                  parent.com_from_mesh, child.com_from_mesh, dt_s));
    world.addConstraint(&joints.back()->constraint(), spec.ignore_inter_collision);
  }
}

void Simulation::Data::build_soft_bodies() {
  for (const SoftBodySpec& spec : model.soft_bodies) {
    const TriangleMesh mesh = load_mesh(spec.mesh, spec.scale);
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
  probe.setCollisionShape(&probe_shape);
  for (std::size_t a = 0; a < model.actuators.size(); ++a) {
    const ActuatorSpec& spec = model.actuators[a];
    ActuatorData actuator;
    actuator.parent = spec.parent;
    actuator.point_in_mesh = to_bt(spec.location.position_m);
    actuators.push_back(std::move(actuator));
    bodies[spec.parent].actuators.push_back(static_cast<int>(a));
  }
}

void Simulation::Data::actuate(ActuatorData& actuator, bool engage) noexcept {
  if (engage == static_cast<bool>(actuator.hold)) return;
  if (!engage) {
    world.removeConstraint(actuator.hold.get());
    actuator.hold.reset();
    return;
  }
  BodyData& parent = bodies[actuator.parent];
  const btTransform mesh = parent.body->getWorldTransform() * parent.com_from_mesh;
  const btVector3 point = mesh * actuator.point_in_mesh;
  probe.setWorldTransform(btTransform(btQuaternion::getIdentity(), point));
  TouchingBody touching(parent.body.get());
  world.contactTest(&probe, touching);
  if (!touching.found) return;  // nothing to hold: stays released
  const ActuatorSpec& spec = model.actuators[&actuator - actuators.data()];
  actuator.hold = std::make_unique<btPoint2PointConstraint>(
      *parent.body, *touching.found, parent.body->getWorldTransform().invXform(point),
      touching.found->getWorldTransform().invXform(point));
  actuator.hold->m_setting.m_impulseClamp = spec.max_impulse;
  actuator.hold->m_setting.m_tau = spec.tau;
  world.addConstraint(actuator.hold.get(), true);
}

void Simulation::Data::apply_cartesian(BodyData& body) noexcept {
  body.applied = {};
  if (!body.commanded) return;
  btRigidBody& rb = *body.body;
  switch (body.type) {
    case CartesianCommandType::kForce:
      rb.applyCentralForce(body.force);
      rb.applyTorque(body.torque);
      body.applied = {from_bt(body.force), from_bt(body.torque)};
      break;
    case CartesianCommandType::kVelocity:
      rb.setLinearVelocity(body.linear_velocity);
      rb.setAngularVelocity(body.angular_velocity);
      break;
    case CartesianCommandType::kPosition: {
      const btTransform target_com = body.target * body.com_from_mesh.inverse();
      if (!body.dynamic) {  // static bodies are moved, as upstream
        rb.setWorldTransform(target_com);
        break;
      }
      const btTransform& now = rb.getWorldTransform();
      const btVector3 linear_error = target_com.getOrigin() - now.getOrigin();
      const btQuaternion delta = target_com.getRotation() * now.getRotation().inverse();
      btVector3 angular_error = delta.getAxis() * delta.getAngle();
      if (delta.getAngle() > SIMD_PI)
        angular_error = delta.getAxis() * (delta.getAngle() - SIMD_2_PI);
      body.linear_integral += linear_error * dt_s;
      body.angular_integral += angular_error * dt_s;
      const btVector3 linear_rate = body.has_previous_error
                                        ? (linear_error - body.previous_linear_error) / dt_s
                                        : btVector3(0, 0, 0);
      const btVector3 angular_rate = body.has_previous_error
                                         ? (angular_error - body.previous_angular_error) / dt_s
                                         : btVector3(0, 0, 0);
      body.previous_linear_error = linear_error;
      body.previous_angular_error = angular_error;
      body.has_previous_error = true;
      const BodySpec& spec = model.bodies[rb.getUserIndex()];
      const Pid& l = spec.linear_controller;
      const Pid& a = spec.angular_controller;
      const btVector3 linear = l.p * linear_error + l.i * body.linear_integral + l.d * linear_rate;
      const btVector3 angular =
          a.p * angular_error + a.i * body.angular_integral + a.d * angular_rate;
      if (spec.controller_output == ControllerOutput::kForce) {
        rb.applyCentralForce(linear);
        rb.applyTorque(angular);
        body.applied = {from_bt(linear), from_bt(angular)};
      } else {
        rb.setLinearVelocity(linear);
        rb.setAngularVelocity(angular);
      }
      break;
    }
  }
}

void Simulation::Data::read_sensors() noexcept {
  for (Ray& ray : rays) {
    const btRigidBody& parent = *bodies[ray.parent].body;
    const btTransform mesh = parent.getWorldTransform() * bodies[ray.parent].com_from_mesh;
    const btVector3 from = mesh * ray.from_in_mesh;
    const btVector3 to = mesh * ray.to_in_mesh;
    SensorRayCallback callback(from, to, &parent);
    world.rayTest(from, to, callback);
    ray.distance_m = callback.hasHit() ? callback.m_closestHitFraction * ray.range_m : -1.0;
  }
}

Simulation::Simulation(const Model& model, double dt_s)
    : data_(std::make_unique<Data>(model, dt_s)) {
  Data& d = *data_;
  d.broadphase.getOverlappingPairCache()->setOverlapFilterCallback(&d.filter);
  d.world.setGravity(to_bt(model.world.gravity_mps2));
  d.world.getWorldInfo().m_gravity = to_bt(model.world.gravity_mps2);
  d.world.getWorldInfo().m_sparsesdf.Initialize();
  d.world.getSolverInfo().m_numIterations = model.world.max_iterations;
  d.build_bodies();
  d.build_joints();
  d.build_soft_bodies();
  d.build_sensors();
  d.build_actuators();
  d.read_sensors();
}

Simulation::~Simulation() = default;

const Model& Simulation::model() const noexcept {
  return data_->model;
}
double Simulation::dt_s() const noexcept {
  return data_->dt_s;
}
std::uint64_t Simulation::step_count() const noexcept {
  return data_->steps;
}
double Simulation::time_s() const noexcept {
  return static_cast<double>(data_->steps) * data_->dt_s;
}

void Simulation::step() noexcept {
  Data& d = *data_;
  for (BodyData& body : d.bodies) d.apply_cartesian(body);
  for (auto& joint : d.joints) joint->apply_control();
  d.world.stepSimulation(d.dt_s, 1, d.dt_s);
  for (auto& joint : d.joints) joint->update_readings();
  d.read_sensors();
  ++d.steps;
}

void Simulation::reset() noexcept {
  Data& d = *data_;
  for (BodyData& body : d.bodies) {
    btRigidBody& rb = *body.body;
    rb.setWorldTransform(body.initial_com);
    rb.setInterpolationWorldTransform(body.initial_com);
    rb.setLinearVelocity(btVector3(0, 0, 0));
    rb.setAngularVelocity(btVector3(0, 0, 0));
    rb.clearForces();
  }
  for (std::size_t b = 0; b < d.bodies.size(); ++b) clear_command(b);
  for (ActuatorData& actuator : d.actuators) d.actuate(actuator, false);
  for (SoftBodyData& soft : d.soft_bodies)
    for (int n = 0; n < soft.body->m_nodes.size(); ++n) {
      soft.body->m_nodes[n].m_x = soft.initial_positions[n];
      soft.body->m_nodes[n].m_v = btVector3(0, 0, 0);
    }
  for (auto& joint : d.joints) joint->update_readings();
  d.steps = 0;
}

void Simulation::set_command(std::size_t index, const BodyCommand& command) noexcept {
  Data& d = *data_;
  BodyData& body = d.bodies[index];
  if (!body.commanded || body.type != command.cartesian_type) {
    body.linear_integral = body.angular_integral = btVector3(0, 0, 0);
    body.has_previous_error = false;
  }
  body.commanded = true;
  body.type = command.cartesian_type;
  body.target = from_pose(command.pose);
  body.force = to_bt(command.wrench.force_n);
  body.torque = to_bt(command.wrench.torque_nm);
  body.linear_velocity = to_bt(command.twist.linear_mps);
  body.angular_velocity = to_bt(command.twist.angular_radps);
  const std::vector<int>& below = d.model.descendant_joints[index];
  body.commanded_joints.clear();  // capacity reserved for every descendant joint
  for (std::uint32_t j = 0; j < command.joint_count && j < below.size(); ++j) {
    d.joints[below[j]]->command(command.joint_types[j], command.joint_values[j]);
    body.commanded_joints.push_back(below[j]);
  }
  for (std::uint32_t a = 0; a < command.actuator_count && a < body.actuators.size(); ++a)
    d.actuate(d.actuators[body.actuators[a]], command.actuate[a] != 0);
}

void Simulation::clear_command(std::size_t index) noexcept {
  BodyData& body = data_->bodies[index];
  body.commanded = false;
  for (int joint : body.commanded_joints) data_->joints[joint]->release();
  body.commanded_joints.clear();
}

void Simulation::hold_command(std::size_t index) noexcept {
  clear_command(index);
  BodyData& body = data_->bodies[index];
  for (int joint : data_->model.descendant_joints[index]) {
    JointModel& model = *data_->joints[joint];
    model.command(JointCommandType::kPosition, model.position());
    body.commanded_joints.push_back(joint);
  }
}

void Simulation::fill_state(std::size_t index, BodyState& state) const noexcept {
  const Data& d = *data_;
  const BodyData& body = d.bodies[index];
  const btRigidBody& rb = *body.body;
  state.pose = to_pose(rb.getWorldTransform() * body.com_from_mesh);
  state.twist = {from_bt(rb.getLinearVelocity()), from_bt(rb.getAngularVelocity())};
  state.wrench = body.applied;
  state.mass_kg = d.model.bodies[index].mass_kg;
  state.principal_inertia_kgm2 = rb.getInvMass() > 0
                                     ? Vec3{1.0 / std::max(rb.getInvInertiaDiagLocal().x(), 1e-300),
                                            1.0 / std::max(rb.getInvInertiaDiagLocal().y(), 1e-300),
                                            1.0 / std::max(rb.getInvInertiaDiagLocal().z(), 1e-300)}
                                     : Vec3{};
  const std::vector<int>& below = d.model.descendant_joints[index];
  const std::size_t count = std::min(below.size(), kMaxJointsPerBody);
  state.joint_count = static_cast<std::uint32_t>(count);
  for (std::size_t j = 0; j < count; ++j) {
    const JointModel& joint = *d.joints[below[j]];
    state.joint_positions[j] = joint.position();
    state.joint_velocities[j] = joint.velocity();
    state.joint_efforts[j] = joint.effort();
  }
  const std::size_t rays = std::min(body.ray_count, kMaxSensorRaysPerBody);
  state.sensor_ray_count = static_cast<std::uint32_t>(rays);
  for (std::size_t r = 0; r < rays; ++r)
    state.sensor_distances_m[r] = d.rays[body.first_ray + r].distance_m;
}

void Simulation::fill_soft_body_state(std::size_t index, BodyState& state) const noexcept {
  const btSoftBody& soft = *data_->soft_bodies[index].body;
  btVector3 centre(0, 0, 0), velocity(0, 0, 0);
  for (int n = 0; n < soft.m_nodes.size(); ++n) {
    centre += soft.m_nodes[n].m_x;
    velocity += soft.m_nodes[n].m_v;
  }
  const btScalar count = std::max(1, soft.m_nodes.size());
  state.pose = {from_bt(centre / count), {}};
  state.twist = {from_bt(velocity / count), {}};
  state.mass_kg = data_->model.soft_bodies[index].mass_kg;
}

Pose Simulation::body_pose(std::size_t index) const noexcept {
  const BodyData& body = data_->bodies[index];
  return to_pose(body.body->getWorldTransform() * body.com_from_mesh);
}

double Simulation::joint_position(std::size_t joint) const noexcept {
  return data_->joints[joint]->position();
}
double Simulation::joint_velocity(std::size_t joint) const noexcept {
  return data_->joints[joint]->velocity();
}
double Simulation::joint_pivot_gap_m(std::size_t joint) const noexcept {
  return data_->joints[joint]->pivot_gap_m();
}

bool Simulation::actuator_engaged(std::size_t actuator) const noexcept {
  return static_cast<bool>(data_->actuators[actuator].hold);
}

bool Simulation::all_finite() const noexcept {
  for (const BodyData& body : data_->bodies) {
    const btRigidBody& rb = *body.body;
    if (!finite(rb.getWorldTransform().getOrigin()) || !finite(rb.getLinearVelocity()) ||
        !finite(rb.getAngularVelocity()) || !std::isfinite(rb.getOrientation().w()))
      return false;
  }
  for (const SoftBodyData& soft : data_->soft_bodies)
    for (int n = 0; n < soft.body->m_nodes.size(); ++n)
      if (!finite(soft.body->m_nodes[n].m_x)) return false;
  return true;
}

const char* command_problem(const BodyCommand& command, std::uint32_t joint_count,
                            std::uint32_t actuator_count) noexcept {
  const auto type = static_cast<std::uint8_t>(command.cartesian_type);
  if (type > 2) return "cartesian_type is not FORCE (0), POSITION (1) or VELOCITY (2)";
  if (command.joint_count > joint_count) return "joint_count is beyond the body's joints";
  if (command.actuator_count > actuator_count)
    return "actuator_count is beyond the body's actuators";
  const Pose& p = command.pose;
  if (!finite(p.position_m) || !std::isfinite(p.orientation.x) || !std::isfinite(p.orientation.y) ||
      !std::isfinite(p.orientation.z) || !std::isfinite(p.orientation.w))
    return "pose holds NaN or Inf";
  if (!finite(command.wrench.force_n) || !finite(command.wrench.torque_nm))
    return "wrench holds NaN or Inf";
  if (!finite(command.twist.linear_mps) || !finite(command.twist.angular_radps))
    return "twist holds NaN or Inf";
  for (std::uint32_t j = 0; j < command.joint_count; ++j) {
    if (!std::isfinite(command.joint_values[j])) return "a joint value is NaN or Inf";
    if (static_cast<std::uint8_t>(command.joint_types[j]) > 2)
      return "a joint type is not EFFORT (0), POSITION (1) or VELOCITY (2)";
  }
  return nullptr;
}

}  // namespace afhub::physics
