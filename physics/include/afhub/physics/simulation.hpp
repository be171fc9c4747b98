// The simulation: a Bullet world built once from a Model, stepped at a fixed dt
// (MuJoCo's mjData, in spirit: everything that changes while simulating lives
// here, allocated when it is built; step() and the readings allocate nothing).
#pragma once

#include <cstdint>
#include <memory>

#include "afhub/physics/model.hpp"
#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"

namespace afhub::physics {

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

  // A command (checked with command_problem first) becomes the body's current
  // one; its joint values go to the body's descendant joints in order.
  void set_command(std::size_t body, const BodyCommand& command) noexcept;
  // Zero wrench and zero effort on the joints this body commanded (the watchdog);
  // its actuators keep what they hold.
  void clear_command(std::size_t body) noexcept;
  // Zero wrench, and every joint below the body held where it is now by its
  // position controller (the watchdog's hold policy).
  void hold_command(std::size_t body) noexcept;

  // Readings of body `body` (an index into model().bodies) and of soft body `soft`.
  void fill_state(std::size_t body, BodyState& state) const noexcept;
  void fill_soft_body_state(std::size_t soft, BodyState& state) const noexcept;
  Pose body_pose(std::size_t body) const noexcept;  // the mesh frame, as `location`
  double joint_position(std::size_t joint) const noexcept;
  double joint_velocity(std::size_t joint) const noexcept;
  double joint_pivot_gap_m(std::size_t joint) const noexcept;
  // False as soon as any body or soft-body node holds a NaN or infinite value.
  bool all_finite() const noexcept;
  // Whether actuator `actuator` (an index into model().actuators) holds a body.
  bool actuator_engaged(std::size_t actuator) const noexcept;

 private:
  struct Data;
  std::unique_ptr<Data> data_;
};

// nullptr when `command` can be applied to a body with `joint_count` joints and
// `actuator_count` actuators; else what is wrong with it (NaN or Inf, a joint or an
// actuator beyond the body's, an unknown type).
const char* command_problem(const BodyCommand& command, std::uint32_t joint_count,
                            std::uint32_t actuator_count = 0) noexcept;

}  // namespace afhub::physics
