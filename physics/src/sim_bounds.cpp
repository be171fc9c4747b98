// The physical bounds of every body's input, derived from the model once (see
// InputBounds in body_input.hpp), and the check of an input against them.
#include <cstdio>

#include "simulation_data.hpp"

namespace afhub::physics {
namespace {

constexpr double kGravity = 9.81;
constexpr double kTwoPi = 2.0 * M_PI;

// hypot: a refused 1e308 is said as 1e308, not as the inf its square overflows to.
double length(const Vec3& v) {
  return std::hypot(v.x, v.y, v.z);
}

}  // namespace

void Simulation::Data::build_bounds() {
  // The reach of the scene: the farthest body origin, or the enclosure's half diagonal.
  double reach = 1.0;
  for (const BodySpec& body : model.bodies)
    reach = std::max(reach, length(body.location.position_m));
  reach = std::max(reach, 0.5 * length(model.world.enclosure_m));
  const double workspace = reach + 10.0;
  // The mass each body carries: itself and every body below it, passive joints
  // included (they are out of the joint lists, not out of the chain).
  std::vector<double> carried(model.bodies.size(), 0.0);
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    std::vector<bool> counted(model.bodies.size(), false);
    std::vector<std::size_t> stack = {b};
    counted[b] = true;
    while (!stack.empty()) {
      const std::size_t body = stack.back();
      stack.pop_back();
      carried[b] += model.bodies[body].mass_kg;
      for (const JointSpec& joint : model.joints)
        if (joint.parent == static_cast<int>(body) && joint.child >= 0 && !counted[joint.child]) {
          counted[joint.child] = true;
          stack.push_back(static_cast<std::size_t>(joint.child));
        }
    }
  }
  bounds.assign(model.bodies.size(), InputBounds{});
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const BodySpec& spec = model.bodies[b];
    InputBounds& out = bounds[b];
    out.workspace_m = workspace;
    out.force_n = std::max(1.0, carried[b]) * 100.0 * kGravity;
    out.torque_nm = out.force_n * reach;
    out.linear_mps = std::max(10.0, spec.linear_controller.p * 2.0 * workspace);
    out.angular_radps = std::max(10.0 * kTwoPi, spec.angular_controller.p * kTwoPi);
    const std::vector<int>& below = model.descendant_joints[b];
    const std::size_t counted = std::min(below.size(), kBodyJointCapacity);
    out.joint_effort.assign(counted, 0.0);
    out.joint_velocity.assign(counted, 0.0);
    out.joint_position.assign(counted, 0.0);
    for (std::size_t k = 0; k < counted; ++k) {
      const JointSpec& joint = model.joints[below[k]];
      const double motor = joint.max_motor_impulse / dt_s;
      const double mass = std::max(1.0, joint.child >= 0 ? carried[joint.child] : 0.0);
      if (is_rotational(joint.type)) {
        out.joint_effort[k] = std::max(motor, 10.0 * mass * kGravity * reach);
        out.joint_velocity[k] = std::max(10.0 * kTwoPi, joint.controller.p * kTwoPi);
        // A continuous joint counts its turns: a hold at its position stays valid.
        out.joint_position[k] = joint.type == JointType::kContinuous ? 1e9 : 100.0;
      } else {
        out.joint_effort[k] = std::max(motor, 10.0 * mass * kGravity);
        out.joint_velocity[k] = std::max(10.0, joint.controller.p * workspace);
        out.joint_position[k] = workspace;
      }
    }
  }
}

const InputBounds& Simulation::input_bounds(std::size_t body) const noexcept {
  return data_->bounds[body];
}

const char* Simulation::input_problem(std::size_t index, const BodyInput& input) const noexcept {
  const Data& d = *data_;
  std::uint32_t actuators = static_cast<std::uint32_t>(d.bodies[index].actuators.size());
  const auto joints = static_cast<std::uint32_t>(d.model.descendant_joints[index].size());
  if (const char* problem = physics::input_problem(input, joints, actuators)) return problem;
  // A chain's link moves only as its joints let it: it can be pushed, not given a
  // velocity (a twist, or a pose through a PID whose output is a velocity).
  if (d.bodies[index].chain >= 0 &&
      (input.cartesian == CartesianMode::kVelocity ||
       (input.cartesian == CartesianMode::kPosition &&
        (d.model.bodies[index].linear_output == ControllerOutput::kVelocity ||
         d.model.bodies[index].angular_output == ControllerOutput::kVelocity))))
    return "the body is a link of a chain in reduced coordinates (--reduced-coordinates), "
           "which takes no velocity: command a wrench, a pose with a force controller, or "
           "its joints";
  const InputBounds& bound = d.bounds[index];
  char* text = d.problem.data();
  const std::size_t size = d.problem.size();
  // Only the fields the Cartesian mode uses are applied, but all are checked: a
  // command carries one meaning, and a huge unused value is a sender's bug too.
  const Vec3& p = input.target_pose.position_m;
  if (length(p) > bound.workspace_m) {
    std::snprintf(text, size,
                  "pose position (%g, %g, %g) m is outside the workspace, %.4g m from the origin",
                  p.x, p.y, p.z, bound.workspace_m);
    return text;
  }
  const Quaternion& q = input.target_pose.orientation;
  const double norm2 = q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w;
  // Zero (an unfilled ROS Pose) was taken as the identity; refused when it is applied,
  // as senders that fill no pose leave it zero.
  if (norm2 > 4.0 || (norm2 < 0.25 && input.cartesian == CartesianMode::kPosition)) {
    std::snprintf(text, size,
                  "pose orientation (%g, %g, %g, %g) is no rotation: a quaternion's norm is 1", q.x,
                  q.y, q.z, q.w);
    return text;
  }
  struct Check {
    const char* field;
    double value, bound;
    const char* unit;
  };
  const Check cartesian[] = {
      {"force", length(input.wrench.force_n), bound.force_n, "N"},
      {"torque", length(input.wrench.torque_nm), bound.torque_nm, "N m"},
      {"linear velocity", length(input.twist.linear_mps), bound.linear_mps, "m/s"},
      {"angular velocity", length(input.twist.angular_radps), bound.angular_radps, "rad/s"},
  };
  for (const Check& c : cartesian)
    if (c.value > c.bound) {
      std::snprintf(text, size, "%s %g %s is beyond the body's bound of %.4g %s", c.field, c.value,
                    c.unit, c.bound, c.unit);
      return text;
    }
  const std::vector<int>& below = d.model.descendant_joints[index];
  for (std::uint32_t j = 0; j < input.joint_count; ++j) {
    const JointSpec& joint = d.model.joints[below[j]];
    const bool turns = is_rotational(joint.type);
    const double value = input.joint_values[j];
    Check c{"position", value, bound.joint_position[j], turns ? "rad" : "m"};
    if (input.joint_modes[j] == JointMode::kEffort)
      c = {"effort", value, bound.joint_effort[j], turns ? "N m" : "N"};
    else if (input.joint_modes[j] == JointMode::kVelocity)
      c = {"velocity", value, bound.joint_velocity[j], turns ? "rad/s" : "m/s"};
    if (std::abs(c.value) > c.bound) {
      std::snprintf(text, size, "joint %u (%s) %s %g %s is beyond its bound of %.4g %s", j,
                    joint.name.c_str(), c.field, c.value, c.unit, c.bound, c.unit);
      return text;
    }
  }
  return nullptr;
}

}  // namespace afhub::physics
