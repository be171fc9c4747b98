// One ADF joint in Bullet: its constraint, built with the paper's Algorithm 2
// frames; its readings (position, velocity, effort, pivot gap); and its control
// (effort, PID position, motor velocity), applied before each step. A joint of a
// chain in reduced coordinates (chains.hpp) is a link's joint coordinate instead of a
// constraint: the same frames, readings and control, through the multibody.
#pragma once

#include <BulletDynamics/Featherstone/btMultiBodyJointLimitConstraint.h>
#include <BulletDynamics/Featherstone/btMultiBodyJointMotor.h>
#include <btBulletDynamicsCommon.h>

#include <memory>
#include <string>

#include "afhub/physics/body_input.hpp"
#include "afhub/physics/model.hpp"

namespace afhub::physics {

class JointModel {
 public:
  // `*_com_from_mesh`: each body's mesh frame seen from its centre of mass. `reduced`:
  // no constraint is made; the joint is a link's until attach().
  JointModel(const JointSpec& spec, btRigidBody& parent, btRigidBody& child,
             const btTransform& parent_com_from_mesh, const btTransform& child_com_from_mesh,
             double dt_s, bool reduced = false);

  // The constraint, or nullptr for a joint in reduced coordinates.
  btTypedConstraint* constraint() { return constraint_.get(); }
  const JointSpec& spec() const { return spec_; }

  // In reduced coordinates: the joint frame in the parent's and the child's centre-of-
  // mass frames (the joint reads zero where they meet: its axis is their z, or x for a
  // prismatic joint), and the coordinate the bodies' poses as built give it.
  const btTransform& frame_in_parent() const { return frame_in_parent_; }
  const btTransform& frame_in_child() const { return frame_in_child_; }
  btVector3 axis_in_child() const { return frame_in_child_.getBasis().getColumn(axis_index_); }
  double coordinate_as_placed() const;
  // Makes the joint link `link`'s of `body`, with a motor and, for a revolute or
  // prismatic joint with limits, its limits, which the world then holds (motor(),
  // limit()).
  void attach(btMultiBody& body, int link);
  btMultiBodyConstraint* motor() { return motor_.get(); }
  btMultiBodyConstraint* limit() { return limit_.get(); }

  // Whether the joint has one axis to command (has_joint_axis): a command to a joint
  // without one (fixed, p2p, cone twist, six dof) is ignored, never fed to a PID.
  bool has_axis() const { return has_joint_axis(spec_.type); }
  // The largest effort the joint applies, commanded or from its PID: AMBF's max
  // motor impulse per step (N m or N).
  double max_effort() const { return spec_.max_motor_impulse / dt_s_; }

  // Control for the coming step; stays until replaced or released.
  void command(JointMode type, double value) noexcept;
  void release() noexcept;  // zero effort, motor off, PID state cleared
  // The position the joint is commanded to (rad or m, with `joint offset`, as
  // position()), or false when it has no position command.
  bool position_target(double& target) const noexcept {
    if (!commanded_ || command_type_ != JointMode::kPosition) return false;
    target = command_value_;
    return true;
  }
  void apply_control() noexcept;
  // Reads position, velocity, effort and pivot gap after a step.
  void update_readings() noexcept;
  // Forgets the turns counted so far (after the bodies were put back), then reads.
  void restart_readings() noexcept;

  double position() const { return position_; }  // rad or m, with `joint offset`
  double velocity() const { return velocity_; }
  double effort() const { return effort_; }  // N m or N; 0 without `enable feedback`
  // Distance between the parent's and the child's pivot along the joint's locked
  // directions (a prismatic joint's slide does not count), in metres, as read after
  // the last step: read with the other readings, on whichever thread reads them.
  double pivot_gap_m() const noexcept { return pivot_gap_m_; }
  // The PID gains in use: the file's, or lower when the file's cannot be stable at
  // this step for the bodies the joint moves (see the constructor).
  const Pid& gains() const { return gains_; }
  double damping() const { return damping_; }  // the file's, or lower (see gains())
  // What the stability cap lowered, with the values used; empty when nothing was.
  const std::string& gain_note() const { return gain_note_; }
  // The cap taken again for `driven`, the inertia the joint drives, when that is
  // larger than its own two bodies' (the constructor's; see limit_gains()).
  void raise_gain_cap(double driven);
  // Its axis as built: the direction, a point on it (the parent's pivot), and whether
  // it turns about it (or slides along it).
  btVector3 world_axis() const;
  btVector3 world_pivot() const;
  bool rotational() const;
  // The smaller of its two bodies' inertias about its axis (a static one does not count).
  double own_inertia() const;

 private:
  // `driven`: `inertia` is raise_gain_cap()'s, the bodies the joint drives.
  void limit_gains(double inertia, bool driven = false);
  void apply_effort(double effort) noexcept;
  void set_motor(bool on, double velocity, double max_impulse) noexcept;
  void update_reduced_readings() noexcept;

  JointSpec spec_;
  btRigidBody& parent_;
  btRigidBody& child_;
  btTransform frame_in_parent_, frame_in_child_;
  int axis_index_ = 2;  // the constraint frame axis the joint moves along
  bool free_linear_[3] = {false, false, false};
  std::unique_ptr<btTypedConstraint> constraint_;
  btJointFeedback feedback_{};
  // In reduced coordinates: the chain and the link the joint moves.
  btMultiBody* multibody_ = nullptr;
  int link_ = -1;
  std::unique_ptr<btMultiBodyJointMotor> motor_;
  std::unique_ptr<btMultiBodyJointLimitConstraint> limit_;
  double dt_s_;
  Pid gains_;
  double damping_ = 0.0;
  std::string gain_note_;

  bool commanded_ = false;
  JointMode command_type_ = JointMode::kEffort;
  double command_value_ = 0.0;
  double integral_ = 0.0;
  double applied_effort_ = 0.0;
  // A hinge's angle, unwrapped: Bullet's reading is within +-pi.
  double hinge_reading_ = 0.0, hinge_angle_ = 0.0;
  bool hinge_read_ = false;

  double position_ = 0.0, velocity_ = 0.0, effort_ = 0.0, pivot_gap_m_ = 0.0;
};

}  // namespace afhub::physics
