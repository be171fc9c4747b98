// Everything a Simulation holds while it runs (MuJoCo's mjData, in spirit): the
// Bullet world and, per body, joint, soft body, sensor ray and actuator, what the
// stages keep between steps. Internal to the simulation; its stages are
//   sim_build.cpp              the Bullet objects, made once from the Model
//   sim_control.cpp            inputs: checked, then applied before each step
//   sim_sensors_actuators.cpp  proximity rays and constraint actuators
//   sim_contacts.cpp           each body's net contact wrench after a step
//   sim_state.cpp              the readings after a step
//   sim_recovery.cpp           bodies put back after a step made them NaN
//   simulation.cpp             construction, the step, reset
#pragma once

#include <BulletSoftBody/btDefaultSoftBodySolver.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <optional>
#include <vector>

#include "afhub/physics/simulation.hpp"
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

// A rigid body and its current Cartesian command.
struct BodyData {
  CollisionShape shape;
  std::unique_ptr<btRigidBody> body;
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
  NanRecoveries nan_recoveries;
  btSphereShape probe{0.01};  // what an actuator feels for: 1 cm around its point

  Data(const Model& m, double dt)
      : model(m),
        dt_s(dt),
        solver(static_cast<int>(m.bodies.size()),
               static_cast<int>(m.joints.size() + m.actuators.size())),
        filter(m) {}
  ~Data() {
    for (auto& joint : joints) world.removeConstraint(&joint->constraint());
    for (auto& actuator : actuators)
      if (actuator.hold) world.removeConstraint(actuator.hold);
    // A build that failed part-way (a mesh it could not read) leaves bodies unmade.
    for (auto& body : bodies)
      if (body.body) world.removeRigidBody(body.body.get());
    for (auto& soft : soft_bodies) {
      world.removeSoftBody(soft.body);
      delete soft.body;
    }
  }

  void build_bodies();
  void build_joints();
  void mark_joint_islands();
  void build_soft_bodies();
  void build_sensors();
  void build_actuators();
  void build_world_objects();
  void build_bounds();
  void actuate(ActuatorData& actuator, bool engage) noexcept;
  int touching_body(int parent, const btVector3& point) const noexcept;
  void apply_cartesian(BodyData& body) noexcept;
  void read_sensors() noexcept;
  void recover_non_finite() noexcept;
  void sum_contacts() noexcept;
  void keep_good_state() noexcept;
  Pose world_object_pose(const WorldObjectData& object) const noexcept;
};

}  // namespace afhub::physics
