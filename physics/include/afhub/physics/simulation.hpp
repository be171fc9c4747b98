// The simulation: a Bullet world built once from a Model, stepped at a fixed dt
// (MuJoCo's mjData, in spirit: everything that changes while simulating lives
// here, allocated when it is built; step(), the inputs and the readings allocate
// nothing). It takes BodyInput and gives BodyReading, its own types: it knows no
// transport (the channel adapter, sim_channels.hpp, does).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "afhub/physics/body_input.hpp"
#include "afhub/physics/body_reading.hpp"
#include "afhub/physics/model.hpp"
#include "afhub/physics/shared_work.hpp"

namespace afhub::physics {

// Bodies put back after a step made them NaN or infinite (Simulation::nan_recoveries).
struct NanEvent {
  std::uint64_t step = 0;  // the step that made it non-finite (1 = the first step)
  std::size_t body = 0;    // into model().bodies, or into model().soft_bodies when `soft`
  bool soft = false;
};
struct NanRecoveries {
  std::uint64_t count = 0;  // bodies put back, one per body per step
  NanEvent first, last;     // valid when count > 0
};

class Simulation {
 public:
  // Builds every body, joint, soft body and sensor; throws afhub::Error when a mesh
  // cannot be read. `dt_s` is the fixed step.
  Simulation(const Model& model, double dt_s);
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  const Model& model() const noexcept;
  double dt_s() const noexcept;
  std::uint64_t step_count() const noexcept;
  double time_s() const noexcept;

  // Applies each body's current command, advances one step, updates joints and sensors.
  void step() noexcept;
  // Everything back to where the model placed it; commands cleared; time zero.
  void reset() noexcept;

  // nullptr when `input` can be applied to body `body`: input_problem's checks, and
  // every value within the body's InputBounds. Else what is wrong, naming the field,
  // the value and the bound ("joint 3 (link3-link4) effort 1e+308 is beyond its
  // bound of 2180 N m"); the text stays valid until the next call.
  const char* input_problem(std::size_t body, const BodyInput& input) const noexcept;
  const InputBounds& input_bounds(std::size_t body) const noexcept;
  // nullptr when no entry of `input` (checked with input_problem first) asks
  // something of a joint without an axis (fixed, p2p, cone twist, six dof: see
  // has_joint_axis). Else what is wrong with the first such entry, naming the joint;
  // set_input ignores these entries, the caller counts the command as refused. A 0
  // (effort, velocity or position: what a full-length command carries for such a
  // joint, `afhub cmd`'s hold included, as it reads 0) asks nothing.
  const char* axisless_entry(std::size_t body, const BodyInput& input) const noexcept;
  // nullptr when every position target of `input` is within its joint's limits; else
  // the first one outside them, named. It is taken, and the joint driven to the nearest
  // limit (a target typed in degrees, or in a ROS convention's other zero, looked taken).
  const char* beyond_limits_entry(std::size_t body, const BodyInput& input) const noexcept;

  // An input (checked with input_problem first) becomes the body's current one;
  // its joint values go to the body's descendant joints in order (an entry for a
  // joint without an axis is ignored: axisless_entry). Each joint
  // remembers which body's input drives it: the last one to command it.
  void set_input(std::size_t body, const BodyInput& input) noexcept;
  // Zero wrench and zero effort on the joints this body's input drives (the
  // watchdog): joints another body commands since keep that body's command. Its
  // actuators keep what they hold.
  void clear_input(std::size_t body) noexcept;
  // Zero wrench, and the joints below the body that no other body drives held where
  // they are now by their position controllers (the watchdog's hold policy).
  void hold_joints(std::size_t body) noexcept;
  // The body whose input drives joint `joint` (an index into model().joints), or -1.
  int joint_driver(std::size_t joint) const noexcept;

  // Readings of body `body` (an index into model().bodies) and of soft body `soft`.
  void read_body(std::size_t body, BodyReading& reading) const noexcept;
  void read_soft_body(std::size_t soft, BodyReading& reading) const noexcept;
  // A soft body's surface for a viewer: its node count, its triangles (node indices,
  // fixed at load), and its node positions written to `xyz` (node_count entries).
  std::size_t soft_body_node_count(std::size_t soft) const noexcept;
  std::vector<std::array<std::uint32_t, 3>> soft_body_faces(std::size_t soft) const;
  void read_soft_body_nodes(std::size_t soft, std::array<float, 3>* xyz) const noexcept;
  Pose body_pose(std::size_t body) const noexcept;  // the mesh frame, as `location`
  // The world file's lights and cameras (indices into model().world.lights and
  // .cameras): looking along their direction, with `up` as their z axis, carried
  // by their parent body when they have one.
  Pose light_pose(std::size_t light) const noexcept;
  Pose camera_pose(std::size_t camera) const noexcept;
  double joint_position(std::size_t joint) const noexcept;
  double joint_velocity(std::size_t joint) const noexcept;
  double joint_pivot_gap_m(std::size_t joint) const noexcept;
  // Bodies simulated as links of open chains in reduced coordinates
  // (WorldSpec::reduced_coordinates); 0 without.
  std::size_t links_in_reduced_coordinates() const noexcept;
  // The position joint `joint` is commanded to (as joint_position), or false when
  // it has no position command now.
  bool joint_position_target(std::size_t joint, double& target) const noexcept;
  // The joint PID gains and damping in use (the file's, or lower where the file's
  // cannot be stable at this dt), and one note per joint whose gains were lowered.
  const Pid& joint_gains(std::size_t joint) const noexcept;
  double joint_damping(std::size_t joint) const noexcept;
  std::vector<std::string> gain_notes() const;
  // Notes, per file whose bodies that overlap as built do not collide (a URDF robot's
  // links, Model::file_parts_overlaps): how many pairs, and the first few.
  const std::vector<std::string>& parted_overlaps() const noexcept;
  // Warnings, "file:line:col: warning: ...", for bodies of different loaded files that
  // overlap as built (two robots loaded at one place): the first step pushes them apart
  // with forces that can blow a robot up. The deepest few, and how many there are.
  std::vector<std::string> overlaps_between_files() const;
  // Warnings for joints whose bodies, as built, put them outside their limits (a URDF's
  // zero pose can be: the Allegro hand's thumb).
  std::vector<std::string> joints_outside_limits() const;
  // False as soon as any body or soft-body node holds a NaN or infinite value.
  // step() never leaves one (see nan_recoveries); this checks that.
  bool all_finite() const noexcept;
  // A step that leaves a body (or a soft body's node) NaN or infinite does not end
  // the world: the body goes back to its pose after the last good step, at rest;
  // its Cartesian input, and the inputs of every joint touching it or driven by
  // it, are released. The count since the start, the first and the last such event.
  const NanRecoveries& nan_recoveries() const noexcept;
  // Islands of joints the solve's helper thread solved since the start
  // (physics/src/parallel_islands.hpp): 0 while the world has few, or while the
  // stepping thread may run on one CPU only.
  std::uint64_t islands_solved_by_helper() const noexcept;
  // Runs every item of `work`, split between the calling thread (0) and, when the world
  // solves its islands on two threads, their helper (1); returns when all are done.
  // From the thread that steps, between steps: publishing a thousand bodies' readings.
  void share(int count, SharedWork& work) noexcept;
  // Items of such work (the joints' readings, the states) the helper ran since the start.
  std::uint64_t items_shared_with_helper() const noexcept;
  // Whether actuator `actuator` (an index into model().actuators) holds a body.
  bool actuator_engaged(std::size_t actuator) const noexcept;

 private:
  struct Data;
  std::unique_ptr<Data> data_;
};

}  // namespace afhub::physics
