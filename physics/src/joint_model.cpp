// Joints in Bullet (see joint_model.hpp).
#include "joint_model.hpp"

#include <BulletDynamics/ConstraintSolver/btGeneric6DofSpring2Constraint.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "frames.hpp"

namespace afhub::physics {
namespace {

// Bullet's own axis for each constraint: a hinge turns about Z, a slider moves
// along X, a cone twists about X, springs act along or about Z.
int constraint_axis(JointType type) {
  switch (type) {
    case JointType::kPrismatic:
    case JointType::kConeTwist:
      return 0;
    default:
      return 2;
  }
}

btVector3 unit(int axis) {
  btVector3 v(0, 0, 0);
  v[axis] = 1;
  return v;
}

bool is_spring(JointType type) {
  return type == JointType::kLinearSpring || type == JointType::kTorsionSpring ||
         type == JointType::kSixDofSpring;
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}

// The inertia a joint effort meets at the child (or parent): about the joint axis
// through the pivot for a rotational joint, the mass for a linear one. `frame` is
// the joint frame in the body's centre-of-mass frame.
double inertia_along(const btRigidBody& body, const btTransform& frame, int axis, bool rotational) {
  if (body.getInvMass() == 0) return 0.0;  // static: infinite, does not limit
  const double mass = 1.0 / body.getInvMass();
  if (!rotational) return mass;
  const btVector3 a = frame.getBasis().getColumn(axis);
  const btVector3 inverse = body.getInvInertiaDiagLocal();
  double about_com = 0.0;
  for (int i = 0; i < 3; ++i)
    if (inverse[i] > 0) about_com += a[i] * a[i] / inverse[i];
  const double distance = frame.getOrigin().cross(a).length();  // COM to the axis
  return about_com + mass * distance * distance;
}

void set_six_dof_limits(btGeneric6DofSpring2Constraint& c, const JointSpec& spec) {
  if (spec.multi_limits) {
    const SixDofLimits& l = *spec.multi_limits;
    c.setLinearLowerLimit(to_bt(l.linear_low));
    c.setLinearUpperLimit(to_bt(l.linear_high));
    c.setAngularLowerLimit(to_bt(l.angular_low));
    c.setAngularUpperLimit(to_bt(l.angular_high));
  } else {
    // No limits given: every direction is free.
    c.setLinearLowerLimit(btVector3(1, 1, 1));
    c.setLinearUpperLimit(btVector3(-1, -1, -1));
    c.setAngularLowerLimit(btVector3(1, 1, 1));
    c.setAngularUpperLimit(btVector3(-1, -1, -1));
  }
}

}  // namespace

JointModel::JointModel(const JointSpec& spec, btRigidBody& parent, btRigidBody& child,
                       const btTransform& parent_com_from_mesh,
                       const btTransform& child_com_from_mesh, double dt_s, bool reduced)
    : spec_(spec), parent_(parent), child_(child), dt_s_(dt_s), gains_(spec.controller) {
  axis_index_ = constraint_axis(spec.type);
  // AMBF's frames, in each body's centre-of-mass frame: the parent's frame turns the
  // constraint axis onto the parent axis (Algorithm 2). The child's frame is that
  // same frame carried into the child: the joint reads zero when the child axis,
  // turned onto the parent axis the short way and then by `offset` about it,
  // leaves the child where it is. Each frame built on its own (constraint axis onto
  // each body's axis) would measure zero from an arbitrary direction about the
  // axis, so a consistent pose could start outside its joint limits and be thrown.
  // Built in the bodies' mesh frames, where the file's axes are written (the two
  // axes are compared there), then carried into their centre-of-mass frames, which
  // may be turned (an inertial offset's rotation, a mesh's principal axes).
  const btVector3 axis = unit(axis_index_);
  const btVector3 parent_axis = to_bt(spec.parent_axis);
  const btVector3 child_axis = to_bt(spec.child_axis);
  const btQuaternion in_parent = rotation_between(axis, parent_axis);
  const btQuaternion child_onto_parent = rotation_between(child_axis, parent_axis);
  const btQuaternion offset(parent_axis.normalized(), spec.offset_rad);
  const btQuaternion in_child = child_onto_parent.inverse() * offset.inverse() * in_parent;
  frame_in_parent_ = parent_com_from_mesh * btTransform(in_parent, to_bt(spec.parent_pivot_m));
  frame_in_child_ = child_com_from_mesh * btTransform(in_child, to_bt(spec.child_pivot_m));
  const btTransform& a = frame_in_parent_;
  const btTransform& b = frame_in_child_;
  if (reduced) {
    limit_gains(own_inertia());
    return;  // attach() reads it
  }

  switch (spec.type) {
    case JointType::kRevolute:
    case JointType::kContinuous: {
      auto hinge = std::make_unique<btHingeConstraint>(parent, child, a, b, true);
      // Bullet wraps hinge limits into +-pi: a range of a turn or more (a UR arm's
      // +-2 pi) would become a lock. Such a range is no limit to the hinge; position
      // targets are still clamped to it.
      if (spec.type == JointType::kRevolute && spec.limit_low &&
          *spec.limit_high - *spec.limit_low < 2.0 * SIMD_PI)
        hinge->setLimit(*spec.limit_low, *spec.limit_high);
      constraint_ = std::move(hinge);
      break;
    }
    case JointType::kPrismatic: {
      auto slider = std::make_unique<btSliderConstraint>(parent, child, a, b, true);
      if (spec.limit_low) {
        slider->setLowerLinLimit(*spec.limit_low);
        slider->setUpperLinLimit(*spec.limit_high);
      } else {
        slider->setLowerLinLimit(1);  // lower above upper: free
        slider->setUpperLinLimit(-1);
      }
      slider->setLowerAngLimit(0);
      slider->setUpperAngLimit(0);
      free_linear_[0] = true;
      constraint_ = std::move(slider);
      break;
    }
    case JointType::kFixed:
      constraint_ = std::make_unique<btFixedConstraint>(parent, child, a, b);
      break;
    case JointType::kP2P:
      constraint_ =
          std::make_unique<btPoint2PointConstraint>(parent, child, a.getOrigin(), b.getOrigin());
      break;
    case JointType::kConeTwist: {
      auto cone = std::make_unique<btConeTwistConstraint>(parent, child, a, b);
      if (spec.multi_limits) {
        const Vec3& l = spec.multi_limits->angular_high;
        cone->setLimit(l.y, l.z, l.x);  // swing about y, swing about z, twist about x
      }
      constraint_ = std::move(cone);
      break;
    }
    case JointType::kLinearSpring:
    case JointType::kTorsionSpring:
    case JointType::kSixDof:
    case JointType::kSixDofSpring: {
      auto six = std::make_unique<btGeneric6DofSpring2Constraint>(parent, child, a, b);
      // Locked by default; the spring's one direction, or the six dof's limits, are free.
      six->setLinearLowerLimit(btVector3(0, 0, 0));
      six->setLinearUpperLimit(btVector3(0, 0, 0));
      six->setAngularLowerLimit(btVector3(0, 0, 0));
      six->setAngularUpperLimit(btVector3(0, 0, 0));
      const double low = spec.limit_low.value_or(1), high = spec.limit_high.value_or(-1);
      const double middle = spec.limit_low ? (low + high) / 2 : 0.0;
      int spring_dofs[6] = {-1, -1, -1, -1, -1, -1};
      if (spec.type == JointType::kLinearSpring) {
        six->setLimit(2, low, high);
        spring_dofs[0] = 2;
        free_linear_[2] = true;
      } else if (spec.type == JointType::kTorsionSpring) {
        six->setLimit(5, low, high);
        spring_dofs[0] = 5;
      } else {
        set_six_dof_limits(*six, spec);
        for (bool& free : free_linear_) free = !spec.multi_limits;
        if (spec.multi_limits) {
          const SixDofLimits& l = *spec.multi_limits;
          const double lows[3] = {l.linear_low.x, l.linear_low.y, l.linear_low.z};
          const double highs[3] = {l.linear_high.x, l.linear_high.y, l.linear_high.z};
          for (int i = 0; i < 3; ++i) free_linear_[i] = lows[i] != highs[i];
        }
        if (spec.type == JointType::kSixDofSpring)
          for (int i = 0; i < 6; ++i) spring_dofs[i] = i;
      }
      for (int dof : spring_dofs) {
        if (dof < 0) continue;
        six->enableSpring(dof, true);
        six->setStiffness(dof, spec.stiffness);
        six->setDamping(dof, spec.damping);
        six->setEquilibriumPoint(dof, spec.equilibrium.value_or(middle));
      }
      constraint_ = std::move(six);
      break;
    }
  }
  if (spec.erp || spec.cfm) {
    for (int axis_param = -1; axis_param < 6; ++axis_param) {
      if (spec.erp) constraint_->setParam(BT_CONSTRAINT_STOP_ERP, *spec.erp, axis_param);
      if (spec.cfm) constraint_->setParam(BT_CONSTRAINT_STOP_CFM, *spec.cfm, axis_param);
    }
  }
  limit_gains(own_inertia());
  if (spec.enable_feedback) {
    // btVector3's constructor leaves it uninitialised: before the first step the
    // reading would be whatever the memory held (a replay caught it differing).
    for (btVector3* v : {&feedback_.m_appliedForceBodyA, &feedback_.m_appliedTorqueBodyA,
                         &feedback_.m_appliedForceBodyB, &feedback_.m_appliedTorqueBodyB})
      v->setZero();
    constraint_->enableFeedback(true);
    constraint_->setJointFeedback(&feedback_);
  }
  update_readings();
}

// A revolute joint's limits are held as a hinge's would be (a range of a turn or more
// is none); in reduced coordinates the limit rows act only once the joint would cross
// a limit within the step, the speculative limit apply_control() makes for a hinge.
void JointModel::attach(btMultiBody& body, int link) {
  multibody_ = &body;
  link_ = link;
  if (has_axis()) motor_ = std::make_unique<btMultiBodyJointMotor>(&body, link, 0.0, 0.0);
  const bool limited = spec_.limit_low && (spec_.type == JointType::kPrismatic ||
                                           (spec_.type == JointType::kRevolute &&
                                            *spec_.limit_high - *spec_.limit_low < 2.0 * SIMD_PI));
  if (limited) {
    limit_ = std::make_unique<btMultiBodyJointLimitConstraint>(&body, link, *spec_.limit_low,
                                                               *spec_.limit_high);
    limit_->setMaxAppliedImpulse(BT_LARGE_FLOAT);  // Bullet's default, 100 N s, would give way
  }
  // Their rows' storage, which Bullet would otherwise make in the first step (and
  // their applied impulses cannot be read before).
  for (btMultiBodyConstraint* c : {static_cast<btMultiBodyConstraint*>(motor_.get()),
                                   static_cast<btMultiBodyConstraint*>(limit_.get())})
    if (c) c->finalizeMultiDof();
  update_readings();
}

double JointModel::coordinate_as_placed() const {
  const btTransform relative = (parent_.getWorldTransform() * frame_in_parent_).inverse() *
                               (child_.getWorldTransform() * frame_in_child_);
  switch (spec_.type) {
    case JointType::kRevolute:
    case JointType::kContinuous: {
      const btVector3 x = relative.getBasis().getColumn(0);  // the child's x, about the z axis
      return std::atan2(x.y(), x.x());
    }
    case JointType::kPrismatic:
      return relative.getOrigin().x();
    default:
      return 0.0;
  }
}

// An effort PID is explicit: with the step dt and an inertia I at the joint, a
// gain P beyond about I / dt^2 (or D beyond I / dt) makes it blow up, which AMBF
// users meet as "joint control explodes with high gains". The gains are capped at
// P <= 0.1 I / dt^2 and D + damping <= 0.5 I / dt (damping is an explicit effort
// on the velocity too), with I the smaller of the two bodies' inertias at the
// joint: a lower bound of what the joint really moves, so the cap errs on the
// stable side. Velocity output goes through Bullet's motor, which the solver
// handles implicitly: its P and D are left as written, the damping still counts.
// The smaller of the joint's two bodies' inertias about its axis (a static one does not
// count): all a joint is sure to move, wherever the solver carries its effort.
double JointModel::own_inertia() const {
  const double at_child = inertia_along(child_, frame_in_child_, axis_index_, rotational());
  const double at_parent = inertia_along(parent_, frame_in_parent_, axis_index_, rotational());
  double inertia = at_child;
  if (at_parent > 0 && (inertia == 0 || at_parent < inertia)) inertia = at_parent;
  return inertia;
}

void JointModel::raise_gain_cap(double driven) {
  if (has_axis() && driven > own_inertia()) limit_gains(driven, true);
}

void JointModel::limit_gains(double inertia, bool driven) {
  gains_ = spec_.controller;
  gain_note_.clear();
  damping_ = is_spring(spec_.type) ? 0.0 : spec_.damping;  // springs damp in Bullet
  if (!has_axis()) {
    damping_ = 0.0;  // no axis to damp about
    return;
  }
  if (inertia <= 0) return;
  const double p_cap = 0.1 * inertia / (dt_s_ * dt_s_);
  const double d_cap = 0.5 * inertia / dt_s_;
  damping_ = std::min(damping_, d_cap);
  std::string lowered;
  auto note = [&](const char* what, double written, double used) {
    if (used >= written) return;
    lowered += (lowered.empty() ? "" : ", ") + std::string(what) + " " + number(written) +
               " lowered to " + number(used);
  };
  if (!is_spring(spec_.type)) note("damping", spec_.damping, damping_);
  if (spec_.controller_output == ControllerOutput::kForce) {
    gains_.p = std::min(gains_.p, p_cap);
    gains_.d = std::min(gains_.d, d_cap - damping_);
    note("P", spec_.controller.p, gains_.p);
    note("D", spec_.controller.d, gains_.d);
  }
  if (!lowered.empty())
    gain_note_ = spec_.where.str() + ": note: joint '" + spec_.name + "': " + lowered +
                 " to be stable at dt " + number(dt_s_) + " s: it moves " + number(inertia) +
                 (rotational() ? " kg m^2" : " kg") +
                 (driven ? " (of the bodies it drives, for any pose)" : "") +
                 ", so P <= 0.1 I/dt^2 = " + number(p_cap) +
                 " and D + damping <= 0.5 I/dt = " + number(d_cap);
}

bool JointModel::rotational() const {
  return is_rotational(spec_.type);
}

btVector3 JointModel::world_axis() const {
  return parent_.getWorldTransform().getBasis() *
         frame_in_parent_.getBasis().getColumn(axis_index_);
}

btVector3 JointModel::world_pivot() const {
  return parent_.getWorldTransform() * frame_in_parent_.getOrigin();
}

void JointModel::command(JointMode type, double value) noexcept {
  if (!has_axis()) return;  // refused (Simulation::axisless_entry says why)
  if (!commanded_ || type != command_type_) integral_ = 0.0;
  commanded_ = true;
  command_type_ = type;
  command_value_ = value;
}

void JointModel::release() noexcept {
  commanded_ = false;
  integral_ = 0.0;
  set_motor(false, 0.0, spec_.max_motor_impulse);
}

void JointModel::set_motor(bool on, double velocity, double max_impulse) noexcept {
  if (motor_) {
    motor_->setVelocityTarget(velocity);
    motor_->setMaxAppliedImpulse(on ? max_impulse : 0.0);
    return;
  }
  const double max_force = max_impulse / dt_s_;
  switch (spec_.type) {
    case JointType::kRevolute:
    case JointType::kContinuous:
      static_cast<btHingeConstraint&>(*constraint_).enableAngularMotor(on, velocity, max_impulse);
      break;
    case JointType::kPrismatic: {
      auto& slider = static_cast<btSliderConstraint&>(*constraint_);
      slider.setPoweredLinMotor(on);
      slider.setTargetLinMotorVelocity(velocity);
      slider.setMaxLinMotorForce(max_force);
      break;
    }
    case JointType::kLinearSpring:
    case JointType::kTorsionSpring: {
      auto& six = static_cast<btGeneric6DofSpring2Constraint&>(*constraint_);
      const int dof = spec_.type == JointType::kLinearSpring ? 2 : 5;
      six.enableMotor(dof, on);
      six.setTargetVelocity(dof, velocity);
      six.setMaxMotorForce(dof, max_force);
      break;
    }
    default:
      break;  // no single motor axis
  }
}

void JointModel::apply_effort(double effort) noexcept {
  if (multibody_) {
    multibody_->addJointTorque(link_, effort);
    return;
  }
  const btVector3 axis = world_axis();
  if (rotational()) {
    child_.applyTorque(axis * effort);
    parent_.applyTorque(-axis * effort);
  } else {
    child_.applyCentralForce(axis * effort);
    parent_.applyCentralForce(-axis * effort);
  }
  if (effort != 0.0) {
    child_.activate();
    parent_.activate();
  }
}

// Efforts, commanded or from the PID, are capped to max_effort(). The PID acts on
// the error's P and I, and on the measured velocity for D, so that a step in the
// target gives no derivative kick; its integral is clamped so that its I term
// alone stays within the cap (no wind-up while the effort saturates). A joint with a
// velocity limit gets no velocity beyond it, and no effort pushing it on once at it.
void JointModel::apply_control() noexcept {
  double effort = 0.0;
  bool motor = false;
  double motor_velocity = 0.0;
  const double cap = max_effort();
  if (commanded_) {
    switch (command_type_) {
      case JointMode::kEffort:
        effort = std::clamp(command_value_, -cap, cap);
        break;
      case JointMode::kVelocity:
        motor = true;
        motor_velocity = command_value_;
        break;
      case JointMode::kPosition: {
        double target = command_value_ - spec_.joint_offset_rad;
        if (spec_.limit_low) target = std::clamp(target, *spec_.limit_low, *spec_.limit_high);
        const double error = target - (position_ - spec_.joint_offset_rad);
        const Pid& pid = gains_;
        integral_ += error * dt_s_;
        if (pid.i > 0) integral_ = std::clamp(integral_, -cap / pid.i, cap / pid.i);
        const double output = pid.p * error + pid.i * integral_ - pid.d * velocity_;
        if (spec_.controller_output == ControllerOutput::kVelocity) {
          motor = true;
          motor_velocity = output;
        } else {
          effort = std::clamp(output, -cap, cap);
        }
        break;
      }
    }
  }
  double motor_impulse = spec_.max_motor_impulse;
  if (const std::optional<double>& fastest = spec_.max_velocity) {
    motor_velocity = std::clamp(motor_velocity, -*fastest, *fastest);
    // An effort goes through the motor instead, toward the cap in its direction with at
    // most that effort: the solver gives all of it while the joint is slower (holding
    // against gravity or a load) and no more than keeps it at the cap. Applied as it was,
    // one step took it past (50 N m on 0.01 kg m^2: 5 rad/s more); cut by the speed it
    // could reach in a step, it lost its hold (a UR5's shoulder sagged 0.4 rad).
    if (effort != 0.0 && !motor) {
      motor = true;
      motor_velocity = std::copysign(*fastest, effort);
      motor_impulse = std::abs(effort) * dt_s_;
      effort = 0.0;  // the motor's push is read back with the constraint's
    }
  }
  // Joint damping, which upstream parses but never applies to hinges and sliders.
  effort -= damping_ * velocity_;
  // Bullet holds a limit only once it is crossed, so a fast joint went a step's
  // travel past it. A joint that would cross a limit within this step is braked by
  // its motor instead, to arrive on the limit (a speculative limit).
  if (spec_.limit_low && !multibody_ &&
      (spec_.type == JointType::kRevolute || spec_.type == JointType::kPrismatic)) {
    const double q = position_ - spec_.joint_offset_rad;
    const double next = q + velocity_ * dt_s_;
    if (velocity_ > 0 && next > *spec_.limit_high) {
      motor = true;
      motor_velocity = std::max(0.0, (*spec_.limit_high - q) / dt_s_);
      motor_impulse = SIMD_INFINITY;
    } else if (velocity_ < 0 && next < *spec_.limit_low) {
      motor = true;
      motor_velocity = std::min(0.0, (*spec_.limit_low - q) / dt_s_);
      motor_impulse = SIMD_INFINITY;
    }
  }
  set_motor(motor, motor_velocity, motor_impulse);
  applied_effort_ = effort;
  if (effort != 0.0) apply_effort(effort);
}

void JointModel::update_readings() noexcept {
  if (multibody_) {
    update_reduced_readings();
    return;
  }
  double position = 0.0;
  switch (spec_.type) {
    case JointType::kRevolute:
    case JointType::kContinuous: {
      // Bullet reads within +-pi; each step's change is far below pi, so the turns
      // are counted: a continuous joint reports many turns.
      const double reading = static_cast<btHingeConstraint&>(*constraint_).getHingeAngle();
      hinge_angle_ = hinge_read_
                         ? hinge_angle_ + std::remainder(reading - hinge_reading_, 2.0 * M_PI)
                         : reading;
      hinge_reading_ = reading;
      hinge_read_ = true;
      position = hinge_angle_;
      break;
    }
    case JointType::kPrismatic: {
      auto& slider = static_cast<btSliderConstraint&>(*constraint_);
      slider.calculateTransforms(parent_.getWorldTransform(), child_.getWorldTransform());
      position = slider.getLinearPos();
      break;
    }
    case JointType::kLinearSpring:
    case JointType::kTorsionSpring: {
      auto& six = static_cast<btGeneric6DofSpring2Constraint&>(*constraint_);
      six.calculateTransforms();
      position = spec_.type == JointType::kLinearSpring ? six.getRelativePivotPosition(2)
                                                        : six.getAngle(2);
      break;
    }
    case JointType::kConeTwist: {
      auto& cone = static_cast<btConeTwistConstraint&>(*constraint_);
      position = cone.getTwistAngle();
      break;
    }
    default:
      break;
  }
  position_ = position + spec_.joint_offset_rad;
  const btTransform pivot_in_parent = parent_.getWorldTransform() * frame_in_parent_;
  btVector3 gap =
      pivot_in_parent.invXform(child_.getWorldTransform() * frame_in_child_.getOrigin());
  for (int i = 0; i < 3; ++i)
    if (free_linear_[i]) gap[i] = 0;
  pivot_gap_m_ = gap.length();
  // Fixed, p2p and six dof joints have no axis to read along; a cone twist reads its twist.
  if (!has_axis() && spec_.type != JointType::kConeTwist) {
    velocity_ = effort_ = 0.0;
    return;
  }
  const btVector3 axis = world_axis();
  if (rotational()) {
    velocity_ = (child_.getAngularVelocity() - parent_.getAngularVelocity()).dot(axis);
  } else {
    // At the pivot, on both bodies: the parent's point there moves with the
    // parent's turn too, which the centres of mass' velocities would miss.
    const btVector3 pivot = child_.getWorldTransform() * frame_in_child_.getOrigin();
    const btVector3 at_child =
        child_.getVelocityInLocalPoint(pivot - child_.getCenterOfMassPosition());
    const btVector3 at_parent =
        parent_.getVelocityInLocalPoint(pivot - parent_.getCenterOfMassPosition());
    velocity_ = (at_child - at_parent).dot(axis);
  }
  if (spec_.enable_feedback) {
    const double reaction = rotational() ? feedback_.m_appliedTorqueBodyB.dot(axis)
                                         : feedback_.m_appliedForceBodyB.dot(axis);
    effort_ = applied_effort_ + reaction;
  } else {
    effort_ = 0.0;
  }
}

// A link's coordinate cannot open: no pivot gap. The effort felt is what was applied
// and what the motor and the limit rows pushed with in the step.
void JointModel::update_reduced_readings() noexcept {
  pivot_gap_m_ = 0.0;
  if (spec_.type == JointType::kFixed) {
    position_ = velocity_ = effort_ = 0.0;
    return;
  }
  position_ = multibody_->getJointPos(link_) + spec_.joint_offset_rad;
  velocity_ = multibody_->getJointVel(link_);
  effort_ = 0.0;
  if (!spec_.enable_feedback) return;
  double impulse = motor_->getAppliedImpulse(0);
  if (limit_) impulse += limit_->getAppliedImpulse(0) - limit_->getAppliedImpulse(1);
  effort_ = applied_effort_ + impulse / dt_s_;
}

void JointModel::restart_readings() noexcept {
  hinge_read_ = false;
  update_readings();
}

}  // namespace afhub::physics
