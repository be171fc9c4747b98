// The model: what an AMBF description says, loaded once and never changed while
// simulating (MuJoCo's mjModel, in spirit). Units are SI; frames as in ambf.md.
#pragma once

#include <optional>
#include <string>
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

struct BodySpec {
  std::string identifier;  // "BODY base": the key joints refer to
  std::string name;        // spaces removed, as AMBF does
  std::string channel;     // "<namespace>/<name>"
  SourceLocation where;
  double mass_kg = 0.0;  // 0: static
  std::optional<Vec3> inertia_kgm2;
  std::optional<Placement> inertial_offset;
  Placement location;
  std::string visual_mesh;     // resolved path, empty when a primitive shape is used
  std::string collision_mesh;  // resolved path, empty when a primitive shape is used
  std::string shape;           // BOX, SPHERE, ... when given
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

struct Pid {
  double p = 0.0, i = 0.0, d = 0.0;
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
  double offset_rad = 0.0;
  double damping = 0.0;
  double stiffness = 0.0;
  double max_motor_impulse = 0.1;
  bool enable_feedback = false;
  bool passive = false;
  std::optional<Pid> controller;
};

struct Model {
  std::vector<BodySpec> bodies;
  std::vector<JointSpec> joints;
  // For each body, every joint below it (paper Algorithm 1), each once, in file order.
  std::vector<std::vector<int>> descendant_joints;
  std::vector<std::string> warnings;  // "file:line:col: warning: ..."
  // Independent closed kinematic loops (joints - bodies + connected groups).
  int closed_loop_count = 0;
};

}  // namespace afhub::physics
