// One ADF joint in Bullet: its constraint, built with the paper's Algorithm 2
// frames; its readings (position, velocity, effort, pivot gap); and its control
// (effort, PID position, motor velocity), applied before each step.
#pragma once

#include <btBulletDynamicsCommon.h>

#include <memory>

#include "afhub/physics/body_input.hpp"
#include "afhub/physics/model.hpp"

namespace afhub::physics {

class JointModel {
 public:
  // `*_com_from_mesh`: each body's mesh frame seen from its centre of mass.
  JointModel(const JointSpec& spec, btRigidBody& parent, btRigidBody& child,
             const btTransform& parent_com_from_mesh, const btTransform& child_com_from_mesh,
             double dt_s);

  btTypedConstraint& constraint() { return *constraint_; }
  const JointSpec& spec() const { return spec_; }

  // Control for the coming step; stays until replaced or released.
  void command(JointMode type, double value) noexcept;
  void release() noexcept;  // zero effort, motor off, PID state cleared
  void apply_control() noexcept;
  // Reads position, velocity and effort after a step.
  void update_readings() noexcept;

  double position() const { return position_; }  // rad or m, with `joint offset`
  double velocity() const { return velocity_; }
  double effort() const { return effort_; }  // N m or N; 0 without `enable feedback`
  // Distance between the parent's and the child's pivot along the joint's locked
  // directions (a prismatic joint's slide does not count), in metres.
  double pivot_gap_m() const noexcept;
  // The PID gains in use: the file's, or lower when the file's cannot be stable at
  // this step for the bodies the joint moves (see the constructor).
  const Pid& gains() const { return gains_; }

 private:
  void limit_gains();
  bool rotational() const;
  btVector3 world_axis() const;
  void apply_effort(double effort) noexcept;
  void set_motor(bool on, double velocity) noexcept;

  JointSpec spec_;
  btRigidBody& parent_;
  btRigidBody& child_;
  btTransform frame_in_parent_, frame_in_child_;
  int axis_index_ = 2;  // the constraint frame axis the joint moves along
  bool free_linear_[3] = {false, false, false};
  std::unique_ptr<btTypedConstraint> constraint_;
  btJointFeedback feedback_{};
  double dt_s_;
  Pid gains_;

  bool commanded_ = false;
  JointMode command_type_ = JointMode::kEffort;
  double command_value_ = 0.0;
  double integral_ = 0.0, previous_error_ = 0.0;
  bool has_previous_error_ = false;
  double applied_effort_ = 0.0;

  double position_ = 0.0, velocity_ = 0.0, effort_ = 0.0;
};

}  // namespace afhub::physics
