// The per-cycle teleoperation law (see teleop_law.hpp). Eigen's fixed-size types
// live on the stack: a cycle allocates nothing.
#include "afhub/teleop/teleop_law.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace afhub::teleop {
namespace {

using Eigen::Quaterniond;
using Eigen::Vector3d;

Vector3d to_eigen(const Vec3& v) {
  return {v.x, v.y, v.z};
}
Vec3 to_vec3(const Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

// A unit quaternion; a zero or non-finite one (a broken sample) reads as no rotation.
Quaterniond to_eigen(const Quaternion& q) {
  Quaterniond out(q.w, q.x, q.y, q.z);
  const double norm = out.norm();
  if (!(norm > 1e-12) || !std::isfinite(norm)) return Quaterniond::Identity();
  out.coeffs() /= norm;
  return out;
}
Quaternion to_quaternion(const Quaterniond& q) {
  return {q.x(), q.y(), q.z(), q.w()};
}

// Fixed-axis roll, pitch, yaw as ADF writes them: Rz(y) Ry(p) Rx(r).
Quaterniond from_rpy(const Vec3& rpy) {
  return Quaterniond(Eigen::AngleAxisd(rpy.z, Vector3d::UnitZ()) *
                     Eigen::AngleAxisd(rpy.y, Vector3d::UnitY()) *
                     Eigen::AngleAxisd(rpy.x, Vector3d::UnitX()));
}

// The rotation `q` as a rotation vector (axis times angle, angle in [0, pi]).
Vector3d rotation_vector(const Quaterniond& q) {
  const Eigen::AngleAxisd turn(q.w() < 0 ? Quaterniond(-q.coeffs()) : q);
  return turn.axis() * turn.angle();
}

bool pressed(std::uint32_t buttons, int index) {
  return index >= 0 && index < 32 && (buttons >> index) & 1U;
}

// Shrinks `v` by `band` in length: zero inside the band, continuous at its edge.
Vector3d deadband(const Vector3d& v, double band) {
  const double length = v.norm();
  if (band <= 0.0) return v;
  if (length <= band) return Vector3d::Zero();
  return v * ((length - band) / length);
}

// `v` with its length at most `limit` (its direction kept); limit <= 0: no limit.
Vector3d clamp_length(const Vector3d& v, double limit) {
  const double length = v.norm();
  if (limit <= 0.0 || length <= limit) return v;
  return v * (limit / length);
}

// `change` with its length at most `most` (>= 0).
Vector3d limit_change(const Vector3d& change, double most) {
  const double length = change.norm();
  if (length <= most) return change;
  return change * (most / length);
}

// The smaller of two limits where 0 means none.
double tighter(double a, double b) {
  if (a <= 0.0) return b;
  if (b <= 0.0) return a;
  return std::min(a, b);
}

}  // namespace

TeleopParams teleop_params(const InputDeviceSpec& spec, const CartesianGains& body_gains) {
  TeleopParams params;
  params.workspace_scale = spec.workspace_scale;
  params.location.position_m = spec.location.position_m;
  params.location.orientation = to_quaternion(from_rpy(spec.location.rpy_rad));
  params.orientation_offset = to_quaternion(from_rpy(spec.orientation_offset_rpy));
  params.body_gains = spec.controller_gain.value_or(body_gains);
  params.haptic_gain_linear = spec.haptic_gain_linear;
  params.haptic_gain_angular = spec.haptic_gain_angular;
  params.deadband_n = spec.deadband_n;
  params.max_force_n = spec.max_force_n.value_or(0.0);
  params.max_jerk_n_per_ms = spec.max_jerk_n_per_ms.value_or(0.0);
  params.buttons = spec.buttons;
  return params;
}

TeleopLaw::TeleopLaw(const TeleopParams& params) : params_(params), origin_(params.location) {}

void TeleopLaw::restart_from(const Pose& origin) noexcept {
  origin_ = origin;
  anchored_ = false;
  have_target_ = false;
  was_clutched_ = false;
  device_wrench_ = {};
}

void TeleopLaw::step(const DeviceState& device, const Pose& body_pose, const Twist& body_twist,
                     double dt_s, TeleopOutput& out, const Wrench& body_contact) noexcept {
  const bool timed = dt_s > 0.0 && std::isfinite(dt_s);
  const ButtonMapping& map = params_.buttons;
  const std::uint32_t buttons = device.buttons;
  const std::uint32_t rising = buttons & ~previous_buttons_;
  previous_buttons_ = buttons;

  // Modes and the gripper, as AMBF's haptic loop reads the buttons.
  constexpr int kModes = 2;
  if (pressed(rising, map.next_mode))
    mode_ = static_cast<TeleopMode>((static_cast<int>(mode_) + 1) % kModes);
  if (pressed(rising, map.prev_mode))
    mode_ = static_cast<TeleopMode>((static_cast<int>(mode_) + kModes - 1) % kModes);
  const bool clutch_mode = mode_ == TeleopMode::kClutchCamera;
  if (!clutch_mode) {
    if (pressed(rising, map.clutch)) jaw_ = std::min(1.0, jaw_ + 0.1);
    if (pressed(rising, map.camera)) jaw_ = std::max(0.0, jaw_ - 0.1);
  }
  double gripper = jaw_;
  if (device.spec.sensed & kDeviceGripper)
    gripper = std::isfinite(device.gripper_angle_rad)
                  ? std::clamp(device.gripper_angle_rad, 0.0, 1.0)
                  : 0.5;
  else if (map.gripper >= 0)
    gripper = pressed(buttons, map.gripper) ? 0.0 : 1.0;
  const bool camera_held = clutch_mode && pressed(buttons, map.camera);
  const bool clutched = held_ || (clutch_mode && (pressed(buttons, map.clutch) || camera_held));

  // The device's pose with its axes turned into the world's (M = location * offset).
  const Quaterniond frame =
      to_eigen(params_.location.orientation) * to_eigen(params_.orientation_offset);
  const Vector3d device_position = frame * to_eigen(device.pose.position_m);
  const Quaterniond device_rotation = frame * to_eigen(device.pose.orientation) * frame.inverse();

  if (!anchored_) {
    anchor_ = {to_vec3(device_position), to_quaternion(device_rotation)};
    anchored_ = true;
  }
  const Pose previous_target = have_target_ ? target_ : origin_;
  Vector3d target_position = to_eigen(previous_target.position_m);
  Quaterniond target_rotation = to_eigen(previous_target.orientation);
  if (!clutched) {
    if (was_clutched_) {  // re-anchor: the target continues from where it held
      anchor_ = {to_vec3(device_position), to_quaternion(device_rotation)};
      origin_ = previous_target;
    }
    target_position = to_eigen(origin_.position_m) +
                      params_.workspace_scale * (device_position - to_eigen(anchor_.position_m));
    target_rotation =
        (device_rotation * to_eigen(anchor_.orientation).inverse()) * to_eigen(origin_.orientation);
    target_rotation.normalize();
  }
  was_clutched_ = clutched;

  // The target's velocity by difference over the time between the device's samples, not
  // between this loop's cycles: after a stall both loops catch up back to back, and a
  // sample's motion over a cycle microseconds long was a kick of the body (once 4 cm off
  // the circle). Cycles with no new sample keep that velocity for one of the device's
  // sample intervals, then assume no motion (a driver that stopped moves nothing).
  const std::int64_t sample_ns = device.header.publish_stamp_ns;
  if (have_target_ && sample_ns > sample_ns_) {
    // (In unsigned arithmetic: a forged stamp's difference may not fit a signed one.)
    sample_interval_s_ = static_cast<double>(static_cast<std::uint64_t>(sample_ns) -
                                             static_cast<std::uint64_t>(sample_ns_)) *
                         1e-9;
    since_sample_s_ = 0.0;
    target_velocity_ =
        to_vec3((target_position - to_eigen(previous_target.position_m)) / sample_interval_s_);
    target_angular_ =
        to_vec3(rotation_vector(target_rotation * to_eigen(previous_target.orientation).inverse()) /
                sample_interval_s_);
  } else {
    if (timed) since_sample_s_ += dt_s;
    if (!have_target_ || since_sample_s_ > sample_interval_s_)
      target_velocity_ = target_angular_ = {};
  }
  sample_ns_ = sample_ns;
  const Vector3d target_velocity = to_eigen(target_velocity_);
  const Vector3d target_angular = to_eigen(target_angular_);
  target_ = {to_vec3(target_position), to_quaternion(target_rotation)};
  have_target_ = true;

  // The body's PD wrench toward the target.
  const Vector3d body_position = to_eigen(body_pose.position_m);
  const Quaterniond body_rotation = to_eigen(body_pose.orientation);
  const Gains& linear = params_.body_gains.linear;
  const Gains& angular = params_.body_gains.angular;
  const Vector3d force = linear.p * (target_position - body_position) +
                         linear.d * (target_velocity - to_eigen(body_twist.linear_mps));
  const Vector3d torque = angular.p * rotation_vector(target_rotation * body_rotation.inverse()) +
                          angular.d * (target_angular - to_eigen(body_twist.angular_radps));

  // The device's force: the haptic gain pulls the hand toward the body. As AMBF does,
  // the gain is kept within the stiffness the device renders stably.
  Vector3d device_force = Vector3d::Zero();
  Vector3d device_torque = Vector3d::Zero();
  if (!clutched) {
    double stiffness = params_.haptic_gain_linear;
    if (device.spec.max_stiffness_npm > 0.0)
      stiffness = std::min(stiffness, device.spec.max_stiffness_npm / params_.workspace_scale);
    Vector3d force_world = Vector3d::Zero();
    Vector3d torque_world = Vector3d::Zero();
    if (params_.feedback != FeedbackSource::kContact) {
      force_world = stiffness * (body_position - target_position);
      torque_world =
          params_.haptic_gain_angular * rotation_vector(body_rotation * target_rotation.inverse());
    }
    if (params_.feedback != FeedbackSource::kProxy) {
      // Per newton of contact, what the proxy gives per newton of the body's controller.
      const double linear_scale = linear.p > 0.0 ? stiffness / linear.p : 0.0;
      const double angular_scale = angular.p > 0.0 ? params_.haptic_gain_angular / angular.p : 0.0;
      force_world += linear_scale * to_eigen(body_contact.force_n);
      torque_world += angular_scale * to_eigen(body_contact.torque_nm);
    }
    const Quaterniond to_device = frame.inverse();
    device_force = to_device * force_world;
    device_torque = to_device * torque_world;
  }
  device_force = clamp_length(deadband(device_force, params_.deadband_n),
                              tighter(params_.max_force_n, device.spec.max_force_n));
  device_torque =
      clamp_length(deadband(device_torque, params_.deadband_n), device.spec.max_torque_nm);
  if (params_.max_jerk_n_per_ms > 0.0) {
    // The change over this cycle is bounded; with no time passed, nothing changes. Both
    // ends are within the max force, and so is every point between them.
    const double most = timed ? params_.max_jerk_n_per_ms * 1000.0 * dt_s : 0.0;
    const Vector3d last_force = to_eigen(device_wrench_.force_n);
    const Vector3d last_torque = to_eigen(device_wrench_.torque_nm);
    device_force = last_force + limit_change(device_force - last_force, most);
    device_torque = last_torque + limit_change(device_torque - last_torque, most);
  }
  if (!device_force.allFinite()) device_force.setZero();
  if (!device_torque.allFinite()) device_torque.setZero();
  device_wrench_ = {to_vec3(device_force), to_vec3(device_torque)};

  out.body_wrench = {to_vec3(force), to_vec3(torque)};
  out.body_target = target_;
  out.device_wrench = device_wrench_;
  out.gripper = gripper;
  out.grasp = gripper < 0.5;
  out.clutched = clutched;
  out.camera_held = camera_held;
  out.mode = mode_;
}

}  // namespace afhub::teleop
