// Everything a Simulation holds while it runs (MuJoCo's mjData, in spirit): the
// Bullet world and, per body, joint, soft body, sensor ray and actuator, what the
// stages keep between steps. Internal to the simulation; its stages are
//   sim_build.cpp              the Bullet objects, made once from the Model
//   sim_chains.cpp             open chains in reduced coordinates
//   sim_control.cpp            inputs: checked, then applied before each step
//   sim_sensors_actuators.cpp  proximity rays and constraint actuators
//   sim_contacts.cpp           each body's net contact wrench after a step
//   sim_state.cpp              the readings after a step
//   sim_recovery.cpp           bodies put back after a step made them NaN
//   simulation.cpp             construction, the step, reset
#pragma once

#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>
#include <BulletSoftBody/btDefaultSoftBodySolver.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "afhub/physics/simulation.hpp"
#include "chains.hpp"
#include "collision_shapes.hpp"
#include "constraint_solver.hpp"
#include "frames.hpp"
#include "joint_model.hpp"
#include "reserved_world.hpp"

namespace afhub::physics {

inline bool finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
inline bool finite(const btVector3& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

inline Pose to_pose(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  return {from_bt(t.getOrigin()), {q.x(), q.y(), q.z(), q.w()}};
}

inline btTransform from_pose(const Pose& pose) {
  const Quaternion& q = pose.orientation;
  btQuaternion rotation(q.x, q.y, q.z, q.w);
  if (rotation.length2() < 1e-12) rotation = btQuaternion::getIdentity();
  return btTransform(rotation.normalized(), to_bt(pose.position_m));
}

// A rigid body and its current Cartesian command. A link of a chain in reduced
// coordinates keeps its btRigidBody out of the world, as the link's mirror: it takes
// the link's pose and velocities after each step, and is read as any body is.
struct BodyData {
  CollisionShape shape;
  std::unique_ptr<btRigidBody> body;
  int chain = -1, link = -1;  // in Data::chains, a link of it
  btTransform com_from_mesh;  // the mesh frame seen from the centre of mass
  btTransform initial_com;
  bool dynamic = false;
  bool commanded = false;
  CartesianMode type = CartesianMode::kForce;
  btTransform target;
  btVector3 force{0, 0, 0}, torque{0, 0, 0}, linear_velocity{0, 0, 0}, angular_velocity{0, 0, 0};
  btVector3 linear_integral{0, 0, 0}, angular_integral{0, 0, 0};
  btVector3 previous_linear_error{0, 0, 0}, previous_angular_error{0, 0, 0};
  bool has_previous_error = false;
  Wrench applied;
  // The last step's contacts on this body (sim_contacts.cpp): the net force, its
  // moment about the world's origin, and the points that pushed.
  btVector3 contact_force{0, 0, 0}, contact_moment_at_origin{0, 0, 0};
  std::uint32_t contact_count = 0;
  std::size_t first_ray = 0, ray_count = 0;  // into Data::rays
  std::vector<int> actuators;                // into Data::actuators, file order
  btTransform good_pose;                     // after the last step that left it finite
  bool left_finite = true;                   // by the last step (recover_non_finite)
};

// An open chain in reduced coordinates (chains.hpp): a btMultiBody with a fixed base at
// its static body's centre of mass, and a collider per link with the link's body's
// shape. Per link, what Bullet's multibody does not do as the rigid world does, applied
// as forces before each step: the body's own gravity where it differs from the
// world's, and its damping (btRigidBody scales its velocities by (1 - damping)^dt a
// step: a force of -rate m v, rate = -ln(1 - damping), decays them alike).
struct ChainData {
  struct Link {
    int body = -1;
    btScalar mass = 0;
    btVector3 inertia{0, 0, 0};                  // principal, as the body's
    btScalar linear_rate = 0, angular_rate = 0;  // 1/s
    btVector3 gravity_correction{0, 0, 0};       // N
  };
  int base = -1;
  std::vector<Link> links;
  std::unique_ptr<btMultiBody> body;
  std::vector<std::unique_ptr<btMultiBodyLinkCollider>> colliders;
  std::vector<btScalar> initial_q, good_q;
  std::uint64_t restored_at = ~std::uint64_t{0};  // the step a NaN recovery put it back in
  // Scratch: each link's velocities in its own frame, the base's first; and Bullet's
  // forward kinematics' (reserved at build: a step allocates nothing).
  std::vector<btVector3> omega, velocity;
  btAlignedObjectArray<btQuaternion> world_to_local;
  btAlignedObjectArray<btVector3> local_origin;
};

// A world file's light or camera, carried by its parent body when it has one.
struct WorldObjectData {
  int parent = -1;    // body index; -1: the world frame
  btTransform local;  // in the parent's mesh frame, or in the world
};

struct SoftBodyData {
  btSoftBody* body = nullptr;  // owned by the world
  std::vector<btVector3> initial_positions;
  std::vector<btVector3> good_positions;  // after the last step that left it finite
};

// A constraint actuator: a point-to-point constraint to whatever body touches it,
// made when commanded and removed when released. Its storage is made with the world,
// so that engaging and releasing allocate nothing.
struct ActuatorData {
  int parent = -1;
  btVector3 point_in_mesh;  // in the parent's mesh frame
  std::unique_ptr<std::optional<btPoint2PointConstraint>> storage;
  btPoint2PointConstraint* hold = nullptr;  // engaged: the constraint in `storage`
  int held = -1;                            // engaged: the body it holds
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
  explicit CollisionFilter(const Model& model)
      : model_(model), ignored_base_(model.bodies.size(), -1), parted_(model.bodies.size()) {}
  // A chain's first link and its static base, when their joint ignores their
  // collisions: a link is no rigid body, so the joint cannot say it (chains.hpp).
  void ignore_base(int link, int base) { ignored_base_[link] = base; }
  // Two bodies that overlap as built and are not to collide (Data::part_overlaps).
  void part(int a, int b) {
    parted_[a].push_back(b);
    parted_[b].push_back(a);
  }
  bool needBroadphaseCollision(btBroadphaseProxy* a, btBroadphaseProxy* b) const override {
    if (!(a->m_collisionFilterGroup & b->m_collisionFilterMask) ||
        !(b->m_collisionFilterGroup & a->m_collisionFilterMask))
      return false;
    const int i = static_cast<const btCollisionObject*>(a->m_clientObject)->getUserIndex();
    const int j = static_cast<const btCollisionObject*>(b->m_clientObject)->getUserIndex();
    if (i < 0 || j < 0) return true;
    if (ignored_base_[i] == j || ignored_base_[j] == i) return false;
    if (std::find(parted_[i].begin(), parted_[i].end(), j) != parted_[i].end()) return false;
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
  std::vector<int> ignored_base_;         // per body
  std::vector<std::vector<int>> parted_;  // per body: the bodies part() keeps it from
};

// Work on chains is shared between the two threads (Simulation::share) in blocks of
// this many (an eight-link arm's mirror is about a microsecond).
constexpr int kChainsPerItem = 4;

struct Simulation::Data {
  const Model& model;
  double dt_s;
  std::uint64_t steps = 0;

  btSoftBodyRigidBodyCollisionConfiguration collision_config;
  btCollisionDispatcher dispatcher{&collision_config};
  btDbvtBroadphase broadphase;
  ConstraintSolver solver;
  btDefaultSoftBodySolver soft_solver;  // before the world, which uses it to the end
  ReservedWorld world{&dispatcher, &broadphase, &solver, &collision_config, soft_solver};
  CollisionFilter filter;

  std::vector<BodyData> bodies;
  std::vector<InputBounds> bounds;  // per body, see body_input.hpp
  std::vector<std::unique_ptr<JointModel>> joints;
  std::vector<int> joint_driver;            // per joint: the body whose input drives it, or -1
  mutable std::array<char, 256> problem{};  // the last input_problem's text
  std::vector<SoftBodyData> soft_bodies;
  std::vector<Ray> rays;
  std::vector<ActuatorData> actuators;
  std::vector<WorldObjectData> lights, cameras;
  std::vector<ChainPlan> chain_plans;  // what build_chains() makes
  std::vector<ChainData> chains;
  std::vector<std::string> parted_overlaps;  // what part_overlaps() did, per file
  NanRecoveries nan_recoveries;
  btSphereShape probe{0.01};  // what an actuator feels for: 1 cm around its point

  Data(const Model& m, double dt)
      : model(m),
        dt_s(dt),
        solver(static_cast<int>(m.bodies.size()),
               static_cast<int>(m.joints.size() + m.actuators.size())),
        filter(m),
        chain_plans(m.world.reduced_coordinates ? plan_chains(m) : std::vector<ChainPlan>{}) {}
  ~Data() {
    for (auto& joint : joints) {
      if (joint->constraint()) world.removeConstraint(joint->constraint());
      for (btMultiBodyConstraint* c : {joint->motor(), joint->limit()})
        if (c) world.removeMultiBodyConstraint(c);
    }
    for (ChainData& chain : chains) {
      for (auto& collider : chain.colliders) world.removeCollisionObject(collider.get());
      world.removeMultiBody(chain.body.get());
    }
    for (auto& actuator : actuators)
      if (actuator.hold) world.removeConstraint(actuator.hold);
    // A build that failed part-way (a mesh it could not read) leaves bodies unmade.
    for (auto& body : bodies)
      if (body.body && body.chain < 0) world.removeRigidBody(body.body.get());
    for (auto& soft : soft_bodies) {
      world.removeSoftBody(soft.body);
      delete soft.body;
    }
  }

  void build_bodies();
  void build_joints();
  // Bodies overlapping as built (sim_overlaps.cpp).
  struct Overlap {
    btCollisionObject *a, *b;  // their user indices: the bodies
    double depth_m;
  };
  bool find_overlaps(const std::function<bool(int, int)>& wanted, double depth_m,
                     std::vector<Overlap>& found, std::size_t& looked_at);
  void part_overlaps();
  void raise_gain_caps();
  void build_chains();
  void mark_joint_islands();
  void build_soft_bodies();
  void build_sensors();
  void build_actuators();
  void build_world_objects();
  void build_bounds();
  void actuate(ActuatorData& actuator, bool engage) noexcept;
  int touching_body(int parent, const btVector3& point) const noexcept;
  void apply_cartesian(BodyData& body) noexcept;
  void push(BodyData& body, const btVector3& force, const btVector3& torque) noexcept;
  void drive_chain(ChainData& chain) noexcept;
  void mirror_chains() noexcept;
  void mirror_chain(ChainData& chain) noexcept;
  void place_chain(ChainData& chain, const std::vector<btScalar>& q) noexcept;
  void read_sensors() noexcept;
  void recover_non_finite() noexcept;
  void sum_contacts() noexcept;
  void keep_good_state() noexcept;
  Pose world_object_pose(const WorldObjectData& object) const noexcept;
};

}  // namespace afhub::physics
