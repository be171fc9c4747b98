// The teleoperation law of one device and its simulated body, one cycle at a time,
// as AMBF's haptic loop does it:
//
//   target  = origin + scale * M (p_device - p_anchor)          (M: the device frame's
//   R_target = M (R_device R_anchor^T) M^T R_origin               rotation in the world)
//   body wrench  = P (target - body) + D (target velocity - body velocity)   (world frame)
//   device force = M^T haptic_gain (body - target)        (pulls the hand to the body)
//
// or, with contact feedback, what the contacts push the multibody with (the physics'
// BodyState.contact_wrench of the body and every body below it, summed at the body's
// origin: subtree_contact.hpp), scaled so that a steady press feels as the proxy does:
//   device force = M^T (haptic_gain / P) contact force      (P: the body's linear gain)
// (the body pressing still on a surface has P (target - body) = -contact force). With
// both, the sum.
//
// The anchor is the first device sample, so the body starts at the origin (the
// location) whatever the device's pose. While the clutch is held the target holds and
// the device gets no force; on release the anchor moves to the device's pose then, so
// the target continues from where it held. The device force is shrunk by the deadband
// (continuous, so it does not chatter at the threshold), clamped to the max force and
// rate-limited by max jerk. step() allocates nothing and never throws.
#pragma once

#include <cstdint>

#include "afhub/shm_layout/device.hpp"
#include "afhub/shm_layout/geometry.hpp"
#include "afhub/teleop/input_device_spec.hpp"

namespace afhub::teleop {

// AMBF's modes that afhub has: the default one (a1 clutches, a2 moves the camera) and
// the gripper jaw one (a1 opens, a2 closes). Next/prev mode buttons cycle through them.
enum class TeleopMode : std::uint8_t { kClutchCamera = 0, kGripperJaw = 1 };

// What the device's force renders: the body's lag behind the proxy (AMBF's), the
// body's contact wrench, or the sum of the two.
enum class FeedbackSource : std::uint8_t { kProxy = 0, kContact = 1, kBoth = 2 };

// The law's parameters, resolved: the spec's values with the body's own gains where the
// spec has none.
struct TeleopParams {
  double workspace_scale{10.0};
  Pose location;                  // the device frame in the world; the first target
  Quaternion orientation_offset;  // the device's axes, turned before mapping
  CartesianGains body_gains;
  double haptic_gain_linear{0.0};
  double haptic_gain_angular{0.0};
  double deadband_n{0.0};
  double max_force_n{0.0};        // 0: none (the device's own maximum still applies)
  double max_jerk_n_per_ms{0.0};  // 0: none
  ButtonMapping buttons;
  FeedbackSource feedback{FeedbackSource::kProxy};
};

// `body_gains` are the root body's own controller gains, used when the spec has no
// "controller gain" (as AMBF does).
TeleopParams teleop_params(const InputDeviceSpec& spec, const CartesianGains& body_gains);

struct TeleopOutput {
  Wrench body_wrench;       // world frame, at the body's origin: a BodyCommand kForce wrench
  Pose body_target;         // the device's proxy: where the law drives the body
  Wrench device_wrench;     // device frame: a DeviceCommand's wrench
  double gripper{0.5};      // 0 closed .. 1 open, over the gripper joints' limits
  bool grasp{false};        // gripper < 0.5: the gripper's constraint actuators hold
  bool clutched{false};     // the target holds and the device gets no force
  bool camera_held{false};  // a2 in the default mode: the viewer moves the paired camera
  TeleopMode mode{TeleopMode::kClutchCamera};
};

class TeleopLaw {
 public:
  explicit TeleopLaw(const TeleopParams& params);

  // One cycle: the newest device sample (its publish stamp times the target's velocity),
  // the body's newest pose and twist (world), the time since the previous cycle (for the
  // force's rate limit), and the multibody's contact wrench (world frame,
  // torque about the body's origin: subtree_contact_wrench) for contact feedback.
  void step(const DeviceState& device, const Pose& body_pose, const Twist& body_twist, double dt_s,
            TeleopOutput& out, const Wrench& body_contact = {}) noexcept;

  // The target's origin for the next first cycle (default: the location), for a body
  // that should be driven from where it is; clears the anchor, and the device's force
  // starts again from none, within the jerk limit.
  void restart_from(const Pose& origin) noexcept;

  // While held (the device's samples are stale: its driver stopped), the law acts as
  // under the clutch: the target holds, the device gets no force, and once let go it
  // re-anchors, so the body continues from where it was held with no jump.
  void hold(bool held) noexcept { held_ = held; }

  // A new driver took the device (restarted within the stale time: its hand may be
  // anywhere): the next step anchors at its pose, as after the clutch, so the body
  // continues from where it is (it was thrown 0.7 m toward the new hand's pose), and the
  // device's force starts again from none, within the jerk limit.
  void re_anchor() noexcept {
    was_clutched_ = true;
    device_wrench_ = {};
  }

 private:
  TeleopParams params_;
  bool anchored_{false};
  bool was_clutched_{false};
  bool held_{false};
  std::uint32_t previous_buttons_{0};
  TeleopMode mode_{TeleopMode::kClutchCamera};
  double jaw_{0.5};
  // Kept as plain values so that the header needs no Eigen.
  Pose origin_;  // the target at the anchor
  Pose anchor_;  // the device's pose (mapped into the world's axes) at the anchor
  Pose target_;  // the previous cycle's target
  bool have_target_{false};
  // The device sample behind target_: its publish stamp, the interval since the one
  // before, the cycles' time since it, and the target's velocity it gave.
  std::int64_t sample_ns_{0};
  double sample_interval_s_{0.0}, since_sample_s_{0.0};
  Vec3 target_velocity_, target_angular_;
  Wrench device_wrench_;  // the previous cycle's device wrench (for the jerk limit)
};

}  // namespace afhub::teleop
