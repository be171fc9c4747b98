// The model: what an AMBF description says, loaded once and never changed while
// simulating (MuJoCo's mjModel, in spirit). Units are SI; frames as in ambf.md.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "afhub/shm_layout/geometry.hpp"

namespace afhub::physics {

// Where something was written: "file:line:col" in messages (1-based).
struct SourceLocation {
  std::string file;
  int line = 0;
  int column = 0;
  std::string str() const;
};

// Position and fixed-axis roll, pitch, yaw, as ADF writes them.
struct Placement {
  Vec3 position_m;
  Vec3 rpy_rad;
};

// Fixed-axis roll, pitch, yaw (about x, then y, then z of the parent frame, as ADF
// and AMBF write them) as a quaternion: the one conversion, with Bullet's maths.
Quaternion rpy_to_quaternion(const Vec3& rpy_rad);

enum class ShapeKind { kBox, kSphere, kCylinder, kCapsule, kCone, kPlane };

// A primitive shape (`shape` + `geometry`, or one entry of a compound shape).
struct ShapeSpec {
  ShapeKind kind = ShapeKind::kBox;
  Vec3 box_size_m;  // full sizes, BOX
  double radius_m = 0.0, height_m = 0.0;
  int axis = 2;           // 0, 1, 2 = X, Y, Z: CYLINDER, CAPSULE, CONE
  Vec3 plane_normal;      // PLANE
  double plane_offset_m;  // PLANE
  Placement offset;       // in the body's mesh frame
};

enum class CollisionMeshType { kConvexHull, kConvexMesh, kTrimesh, kPointCloud };

struct Pid {
  double p = 0.0, i = 0.0, d = 0.0;
};

enum class ControllerOutput { kForce, kVelocity };

// Where a joint's PID gains come from: AMBF's default (its file gives no
// `controller`), its file, or `afhub run --default-gains` / `--gains`.
enum class GainSource { kAmbfDefault, kFile, kCommandLine };

// A mesh file placed in a body's mesh frame, with its own scale per axis (a URDF
// mesh's `scale` may differ per axis and per mesh).
struct PlacedMesh {
  std::string path;  // resolved
  Placement offset;
  Vec3 scale{1.0, 1.0, 1.0};
};

constexpr Vec3 uniform_scale(double scale) {
  return {scale, scale, scale};
}

struct BodySpec {
  std::string identifier;  // "BODY base": the key joints refer to
  // "<namespace>/<identifier>" ("/ambf/env/BODY base"): how other files may name it.
  std::string qualified_identifier;
  std::string name;     // spaces removed, as AMBF does; a copy's has its index appended
  std::string channel;  // "<namespace>/<name>"
  SourceLocation where;
  int file_index = 0;    // which loaded file defined it
  double mass_kg = 0.0;  // 0: static
  std::optional<Vec3> inertia_kgm2;
  std::optional<Placement> inertial_offset;
  Placement location;
  std::string visual_mesh;  // resolved path, at the body's frame; empty when shapes are used
  // Further visual meshes, each at its offset (a URDF link's <visual> elements away from
  // the link frame or beyond its first; ADF's `visual meshes`, an afhub extension).
  std::vector<PlacedMesh> visual_mesh_parts;
  std::vector<ShapeSpec> visual_shapes;
  std::string collision_mesh;  // resolved path; empty when shapes are used
  CollisionMeshType collision_mesh_type = CollisionMeshType::kTrimesh;
  std::vector<ShapeSpec> collision_shapes;  // empty: the collision mesh, else the visual shapes
  // Further collision meshes, each at its offset (a URDF link's several <collision>
  // elements; ADF's `collision meshes`, an afhub extension): with any, the body
  // collides as one compound of the collision mesh, these and the collision shapes.
  std::vector<PlacedMesh> collision_mesh_parts;
  std::optional<Placement> collision_offset;
  double scale = 1.0;
  bool passive = false;
  double static_friction = 0.5;
  double rolling_friction = 0.01;
  double linear_damping = 0.04;
  double angular_damping = 0.1;
  double restitution = 0.1;
  double collision_margin = 0.001;
  std::vector<int> collision_groups;
  std::optional<Vec3> gravity_mps2;
  // Cartesian controller for POSITION commands: gains a file gives drive a force (or what
  // `controller output type` says), as AMBF loads them; without them a velocity, P 10 and
  // no D, AMBF's preset for a velocity output (one AMBF version gives D 1, on which a D
  // term acting on the velocity the controller sets itself diverges: a free body given a
  // pose went to 8e9 m).
  Pid linear_controller{10.0, 0.0, 0.0}, angular_controller{10.0, 0.0, 0.0};
  ControllerOutput linear_output = ControllerOutput::kVelocity;
  ControllerOutput angular_output = ControllerOutput::kVelocity;
  std::optional<std::array<double, 4>> color_rgba;  // kept for a future viewer
  std::string color_name;
};

enum class JointType {
  kRevolute,
  kContinuous,
  kPrismatic,
  kFixed,
  kP2P,
  kLinearSpring,
  kTorsionSpring,
  kConeTwist,
  kSixDof,
  kSixDofSpring,
};
const char* joint_type_name(JointType type);
// Whether the joint's coordinate is an angle (rad) rather than a length (m).
bool is_rotational(JointType type);
// Whether the joint moves along or about one axis (revolute, continuous, prismatic,
// the two 1-DOF springs), so that an effort, a velocity or a position means
// something. Fixed, p2p, cone twist and six dof joints have no such axis: commands
// to them are refused.
bool has_joint_axis(JointType type);

// Per-axis limits of a six dof joint; a cone twist's {x, y, z} go in angular_high.
struct SixDofLimits {
  Vec3 linear_low, linear_high, angular_low, angular_high;
};

// A URDF <mimic>: the joint is driven to multiplier * position(joint) + offset.
struct Mimic {
  int joint = -1;  // index into Model::joints
  double multiplier = 1.0;
  double offset = 0.0;
};

struct JointSpec {
  std::string identifier;
  std::string name;
  std::string channel;  // "<namespace>/<name>"
  SourceLocation where;
  int parent = -1;  // index into Model::bodies
  int child = -1;
  Vec3 parent_pivot_m, parent_axis, child_pivot_m, child_axis;
  JointType type = JointType::kRevolute;
  std::optional<double> limit_low, limit_high;
  std::optional<SixDofLimits> multi_limits;  // cone twist, six dof
  double offset_rad = 0.0;                   // child rotation about the axis at joint zero
  double joint_offset_rad = 0.0;             // added to the reported position
  double damping = 0.0;
  double stiffness = 0.0;
  std::optional<double> equilibrium;  // default: mid-limits
  double max_motor_impulse = 0.1;
  // The fastest its motor drives it (rad/s or m/s; URDF's <limit velocity>, ADF's afhub
  // key "max velocity"): velocity commands are capped to it, and no effort of the motor
  // pushes it faster. None: no cap.
  std::optional<double> max_velocity;
  std::optional<double> erp, cfm;
  bool ignore_inter_collision = true;
  bool enable_feedback = false;
  bool passive = false;            // out of every body's joint list: not reported, not commanded
  Pid controller{10.0, 0.0, 1.0};  // joint PID for position commands
  GainSource gains_from = GainSource::kAmbfDefault;
  ControllerOutput controller_output = ControllerOutput::kForce;
  std::optional<Mimic> mimic;  // its position commands come from the joint it mimics
};

// Soft body: a rigid body's placement and mass, its mesh, Bullet's btSoftBody config.
struct SoftBodySpec {
  std::string identifier, name, channel;
  SourceLocation where;
  double mass_kg = 0.0;
  Placement location;
  double scale = 1.0;
  std::string mesh;  // resolved path
  // Bullet btSoftBody::Config / Material fields, by their ADF names (kLST, kDP, ...).
  std::vector<std::pair<std::string, double>> config;
  std::vector<int> fixed_nodes;
  int bending_constraint = 0;  // 0: none, else the distance in links
  int clusters = 0;
};

struct SensorSpec {
  std::string identifier, name;
  SourceLocation where;
  int parent = -1;  // body index
  Placement location;
  double range_m = 0.5;
  std::vector<std::pair<Vec3, Vec3>> rays;  // (offset, direction) in the sensor frame
};

struct ActuatorSpec {
  std::string identifier, name;
  SourceLocation where;
  int parent = -1;
  Placement location;
  double max_impulse = 10.0;
  double tau = 1.0;
};

// A world file's light or camera: its pose is published in the world state.
struct WorldObjectSpec {
  std::string key;   // its block key in the world file ("camera1"): input devices pair by it
  std::string name;  // "<namespace>/<name>"
  Vec3 position_m;
  Vec3 direction;  // light direction, or camera look-at minus location
  Vec3 up{0.0, 0.0, 1.0};
  std::string parent;  // empty: world frame
  SourceLocation parent_at;
};

struct WorldSpec {
  std::string file;  // empty: no world file
  Vec3 gravity_mps2{0.0, 0.0, -9.81};
  Vec3 enclosure_m{0.0, 0.0, 0.0};
  int max_iterations = 20;  // solver iterations; Bullet has 10, which lets a loop open 2 mm
  // Islands of joints are solved directly, not by the iterations above
  // (physics/src/constraint_solver.hpp); false: iterated like the rest.
  bool direct_solve = true;
  // Threads that solve a step's islands of joints: 2 (the most), a helper beside the
  // stepping thread when there are many (physics/src/parallel_islands.hpp); 1, the
  // stepping thread alone.
  int solver_threads = 2;
  // Open chains hanging from a static body are simulated in reduced coordinates
  // (Bullet's btMultiBody: a joint coordinate per joint, no constraint rows to hold
  // them together), which steps many arms in about half the time (docs/performance.md).
  // Which chains qualify: physics/src/chains.hpp. Off by default: `afhub run
  // --reduced-coordinates`.
  bool reduced_coordinates = false;
  std::vector<WorldObjectSpec> lights, cameras;
};

struct Model {
  WorldSpec world;
  std::vector<BodySpec> bodies;
  std::vector<JointSpec> joints;
  std::vector<SoftBodySpec> soft_bodies;
  std::vector<SensorSpec> sensors;
  std::vector<ActuatorSpec> actuators;
  std::vector<bool> file_ignores_inter_collision;  // per loaded file
  // Per loaded file: its bodies that overlap as built do not collide with each other (a
  // URDF's: MoveIt's rule for a robot's default pose).
  std::vector<bool> file_parts_overlaps;
  // Files read besides the blocks' and the world's: the launch file and its color
  // config (a recording names every file a run came from).
  std::vector<std::string> other_files;
  // For each body, every joint below it (paper Algorithm 1), each once, in file
  // order, passive joints left out (as AMBF's active child-joint list): the order of
  // its state's joints and of its command's.
  std::vector<std::vector<int>> descendant_joints;
  std::vector<std::string> warnings;  // "file:line:col: warning: ..."
  // What a loader chose that `afhub check` says ("file: root link 'base' is fixed ...").
  std::vector<std::string> notes;
  // Independent closed kinematic loops (joints - bodies + connected groups).
  int closed_loop_count = 0;
};

// Gravity, by AMBF's rule: a body's own `gravity` wins, then its file's header
// `gravity` (already copied into the body's by the loader), then the world file's.
Vec3 effective_gravity(const Model& model, std::size_t body);
// Every file the model came from (each block's, the world's, other_files), absolute,
// each once, sorted: what a recording names.
std::vector<std::string> model_files(const Model& model);

// The body a light's or camera's `parent` names ("/ambf/env/BODY LightCone": the body
// "BODY LightCone"), or -1 when none is loaded.
int world_object_parent(const Model& model, const WorldObjectSpec& object);

// Whether principal inertias are those of some mass distribution: each at most the sum
// of the others, with 1 % of room (CAD exports round). Bullet takes others, and spins
// such a body in ways no real one does: the model readers warn.
bool possible_principal_inertias(const Vec3& inertia_kgm2);

// `afhub run --gravity`: one gravity for the world and every body, over both rules.
void override_gravity(Model& model, const Vec3& gravity_mps2);

// Puts every body, soft body and joint channel under `prefix` ("copy" makes
// "afhub/arm/base" "copy/afhub/arm/base"), so that two copies of a model can run side
// by side. Throws afhub::Error when a name gets too long for a channel.
void prefix_channels(Model& model, std::string_view prefix);

}  // namespace afhub::physics
