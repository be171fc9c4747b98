// Control: a body's input, once checked (input_problem), becomes its current one:
// its joint values go to its descendant joints in order, its actuators hold or let
// go. Before each step its Cartesian input is applied as a force, a velocity or
// through its PID; the watchdog clears an input or holds the joints where they are.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "simulation_data.hpp"

namespace afhub::physics {

void Simulation::set_input(std::size_t index, const BodyInput& input) noexcept {
  Data& d = *data_;
  BodyData& body = d.bodies[index];
  if (!body.commanded || body.type != input.cartesian) {
    body.linear_integral = body.angular_integral = btVector3(0, 0, 0);
    body.has_previous_error = false;
  }
  body.commanded = true;
  body.type = input.cartesian;
  body.target = from_pose(input.target_pose);
  body.force = to_bt(input.wrench.force_n);
  body.torque = to_bt(input.wrench.torque_nm);
  body.linear_velocity = to_bt(input.twist.linear_mps);
  body.angular_velocity = to_bt(input.twist.angular_radps);
  const std::vector<int>& below = d.model.descendant_joints[index];
  for (std::uint32_t j = 0; j < input.joint_count && j < below.size(); ++j) {
    JointModel& joint = *d.joints[below[j]];
    if (!joint.has_axis()) continue;  // refused: axisless_entry
    joint.command(input.joint_modes[j], input.joint_values[j]);
    d.joint_driver[below[j]] = static_cast<int>(index);
  }
  for (std::uint32_t a = 0; a < input.actuator_count && a < body.actuators.size(); ++a)
    d.actuate(d.actuators[body.actuators[a]], input.engage[a]);
}

void Simulation::clear_input(std::size_t index) noexcept {
  Data& d = *data_;
  d.bodies[index].commanded = false;
  // Only the joints this body drives: a joint below it that another body (a
  // descendant with its own controller) commanded since stays with that body.
  for (int joint : d.model.descendant_joints[index])
    if (d.joint_driver[joint] == static_cast<int>(index)) {
      d.joints[joint]->release();
      d.joint_driver[joint] = -1;
    }
}

void Simulation::hold_joints(std::size_t index) noexcept {
  clear_input(index);
  Data& d = *data_;
  for (int joint : d.model.descendant_joints[index]) {
    if (d.joint_driver[joint] >= 0) continue;  // another body drives it
    JointModel& model = *d.joints[joint];
    if (!model.has_axis()) continue;  // nothing to hold about
    model.command(JointMode::kPosition, model.position());
    d.joint_driver[joint] = static_cast<int>(index);
  }
}

const char* Simulation::axisless_entry(std::size_t index, const BodyInput& input) const noexcept {
  const Data& d = *data_;
  const std::vector<int>& below = d.model.descendant_joints[index];
  for (std::uint32_t j = 0; j < input.joint_count && j < below.size(); ++j) {
    const JointSpec& joint = d.model.joints[below[j]];
    if (has_joint_axis(joint.type)) continue;
    if (input.joint_values[j] == 0.0) continue;  // what a full-length command carries
    std::snprintf(d.problem.data(), d.problem.size(),
                  "joint %u (%s) is %s: it has no single axis to command, so its entry was "
                  "ignored; send 0 for it",
                  j, joint.name.c_str(), joint_type_name(joint.type));
    return d.problem.data();
  }
  return nullptr;
}

const char* Simulation::beyond_limits_entry(std::size_t index,
                                            const BodyInput& input) const noexcept {
  const Data& d = *data_;
  const std::vector<int>& below = d.model.descendant_joints[index];
  for (std::uint32_t j = 0; j < input.joint_count && j < below.size(); ++j) {
    const JointSpec& joint = d.model.joints[below[j]];
    if (input.joint_modes[j] != JointMode::kPosition || !joint.limit_low ||
        !has_joint_axis(joint.type))
      continue;
    const double target = input.joint_values[j] - joint.joint_offset_rad;
    // A joint held where it rests (what `afhub cmd` sends for the joints it is not
    // given), on a limit Bullet lets it sink past a little or outside them as built, is
    // no mistake of the sender's.
    const double slack =
        0.05 * (*joint.limit_high - *joint.limit_low) + (is_rotational(joint.type) ? 0.01 : 0.001);
    if (target >= *joint.limit_low - slack && target <= *joint.limit_high + slack) continue;
    if (std::abs(input.joint_values[j] - d.joints[below[j]]->position()) <= slack) continue;
    std::snprintf(d.problem.data(), d.problem.size(),
                  "joint %u (%s): position target %.6g is outside its limits [%.6g, %.6g] %s, "
                  "so it is driven to the nearest",
                  j, joint.name.c_str(), input.joint_values[j],
                  *joint.limit_low + joint.joint_offset_rad,
                  *joint.limit_high + joint.joint_offset_rad,
                  is_rotational(joint.type) ? "(rad, not degrees)" : "(m)");
    return d.problem.data();
  }
  return nullptr;
}

std::vector<std::string> Simulation::joints_outside_limits() const {
  std::vector<std::string> warnings;
  const Data& d = *data_;
  for (std::size_t j = 0; j < d.joints.size(); ++j) {
    const JointSpec& joint = d.model.joints[j];
    if (!joint.limit_low || !has_joint_axis(joint.type)) continue;
    const double q = d.joints[j]->position() - joint.joint_offset_rad;
    const double slack = 1e-4 + 1e-6 * (*joint.limit_high - *joint.limit_low);
    if (q >= *joint.limit_low - slack && q <= *joint.limit_high + slack) continue;
    char text[256];
    std::snprintf(
        text, sizeof text,
        ": warning: joint '%s' is built at %.4f %s, outside its limits [%.6g, %.6g]: "
        "the first steps throw it within them",
        joint.name.c_str(), d.joints[j]->position(), is_rotational(joint.type) ? "rad" : "m",
        *joint.limit_low + joint.joint_offset_rad, *joint.limit_high + joint.joint_offset_rad);
    warnings.push_back(joint.where.str() + text);
  }
  return warnings;
}

int Simulation::joint_driver(std::size_t joint) const noexcept {
  return data_->joint_driver[joint];
}

// A force at the centre of mass and a torque, on a rigid body or a chain's link.
void Simulation::Data::push(BodyData& body, const btVector3& force,
                            const btVector3& torque) noexcept {
  if (body.chain >= 0) {
    chains[body.chain].body->addLinkForce(body.link, force);
    chains[body.chain].body->addLinkTorque(body.link, torque);
  } else {
    body.body->applyCentralForce(force);
    body.body->applyTorque(torque);
  }
}

void Simulation::Data::apply_cartesian(BodyData& body) noexcept {
  body.applied = {};
  if (!body.commanded) return;
  btRigidBody& rb = *body.body;
  switch (body.type) {
    case CartesianMode::kForce:
      push(body, body.force, body.torque);
      body.applied = {from_bt(body.force), from_bt(body.torque)};
      break;
    case CartesianMode::kVelocity:
      rb.setLinearVelocity(body.linear_velocity);
      rb.setAngularVelocity(body.angular_velocity);
      break;
    case CartesianMode::kPosition: {
      const btTransform target_com = body.target * body.com_from_mesh.inverse();
      if (!body.dynamic) {  // static bodies are moved, as upstream, with their chains
        rb.setWorldTransform(target_com);
        for (ChainData& chain : chains)
          if (chain.base == rb.getUserIndex()) chain.body->setBaseWorldTransform(target_com);
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
      // Each part drives a force (pushed, as a FORCE command is) or sets a velocity.
      const bool push_linear = spec.linear_output == ControllerOutput::kForce;
      const bool push_angular = spec.angular_output == ControllerOutput::kForce;
      const btVector3 force = push_linear ? linear : btVector3(0, 0, 0);
      const btVector3 torque = push_angular ? angular : btVector3(0, 0, 0);
      if (push_linear || push_angular) {
        push(body, force, torque);
        body.applied = {from_bt(force), from_bt(torque)};
      }
      if (!push_linear) rb.setLinearVelocity(linear);
      if (!push_angular) rb.setAngularVelocity(angular);
      break;
    }
  }
}

const char* input_problem(const BodyInput& input, std::uint32_t joint_count,
                          std::uint32_t actuator_count) noexcept {
  if (static_cast<std::uint8_t>(input.cartesian) > 2)
    return "cartesian_type is not FORCE (0), POSITION (1) or VELOCITY (2)";
  if (input.joint_count > joint_count || input.joint_count > kBodyJointCapacity)
    return "joint_count is beyond the body's joints";
  if (input.actuator_count > actuator_count || input.actuator_count > kBodyActuatorCapacity)
    return "actuator_count is beyond the body's actuators";
  const Pose& p = input.target_pose;
  if (!finite(p.position_m) || !std::isfinite(p.orientation.x) || !std::isfinite(p.orientation.y) ||
      !std::isfinite(p.orientation.z) || !std::isfinite(p.orientation.w))
    return "pose holds NaN or Inf";
  if (!finite(input.wrench.force_n) || !finite(input.wrench.torque_nm))
    return "wrench holds NaN or Inf";
  if (!finite(input.twist.linear_mps) || !finite(input.twist.angular_radps))
    return "twist holds NaN or Inf";
  for (std::uint32_t j = 0; j < input.joint_count; ++j) {
    if (!std::isfinite(input.joint_values[j])) return "a joint value is NaN or Inf";
    if (static_cast<std::uint8_t>(input.joint_modes[j]) > 2)
      return "a joint type is not EFFORT (0), POSITION (1) or VELOCITY (2)";
  }
  return nullptr;
}

}  // namespace afhub::physics
