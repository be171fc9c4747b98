// The teleoperation law, cycle by cycle: the device's motion maps onto the body's
// target (scaled, in the location's frame), the clutch holds and releases without a
// jump, the body's PD wrench, and the device force: opposing, dead-banded, bounded and
// rate-limited. A cycle allocates nothing.
#include "afhub/teleop/teleop_law.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <numbers>
#include <random>

#include "heap_counter.hpp"

namespace afhub::teleop {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDt = 0.001;

Vec3 v3(double x, double y, double z) {
  return {x, y, z};
}
double norm(const Vec3& v) {
  return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
}
Vec3 sub(const Vec3& a, const Vec3& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
double dot(const Vec3& a, const Vec3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

// A rotation of `angle` about z, as a quaternion.
Quaternion about_z(double angle) {
  return {0, 0, std::sin(angle / 2), std::cos(angle / 2)};
}

// A device sample; each one published kDt after the one before.
DeviceState device_at(const Vec3& position, std::uint32_t buttons = 0,
                      Quaternion orientation = {}) {
  static std::int64_t published_ns = 0;
  DeviceState device;
  device.header.publish_stamp_ns = published_ns += static_cast<std::int64_t>(kDt * 1e9);
  device.pose.position_m = position;
  device.pose.orientation = orientation;
  device.buttons = buttons;
  return device;
}

Pose pose_at(const Vec3& position, Quaternion orientation = {}) {
  return {position, orientation};
}

TeleopParams plain_params() {
  TeleopParams params;
  params.workspace_scale = 10.0;
  params.body_gains = {{100.0, 10.0}, {5.0, 1.0}};
  params.haptic_gain_linear = 10.0;
  return params;
}

// Whether a and b agree within `tolerance` in every component.
::testing::AssertionResult near(const Vec3& a, const Vec3& b, double tolerance) {
  if (std::abs(a.x - b.x) <= tolerance && std::abs(a.y - b.y) <= tolerance &&
      std::abs(a.z - b.z) <= tolerance)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "(" << a.x << ", " << a.y << ", " << a.z << ") vs ("
                                       << b.x << ", " << b.y << ", " << b.z << ")";
}

TEST(TeleopLaw, ACircleOfTheDeviceGivesTargetsOnTheScaledCircleInTheLocationsFrame) {
  // From the spec as read: yaw 90 degrees, so device x is world y and device y is world -x.
  InputDeviceSpec spec;
  spec.workspace_scale = 5.0;
  spec.location = {v3(0.2, 0.5, -0.1), v3(0, 0, kPi / 2)};
  const TeleopParams params = teleop_params(spec, {{100, 10}, {5, 1}});
  TeleopLaw law(params);
  const Vec3 centre = v3(0.01, 0.0, 0.02);
  const double radius = 0.03;
  auto on_circle = [&](int i) {
    const double angle = 2 * kPi * i / 200;
    return v3(centre.x + radius * std::cos(angle), centre.y + radius * std::sin(angle), centre.z);
  };
  const Vec3 first = on_circle(0);
  // The world's image of a device displacement d: 5 * Rz(90) d = 5 * (-d.y, d.x, d.z).
  auto expected_target = [&](const Vec3& p) {
    const Vec3 d = sub(p, first);
    return v3(0.2 - 5 * d.y, 0.5 + 5 * d.x, -0.1 + 5 * d.z);
  };
  const Vec3 world_centre = expected_target(centre);
  TeleopOutput out;
  for (int i = 0; i <= 200; ++i) {
    const Vec3 p = on_circle(i);
    law.step(device_at(p), pose_at(v3(0, 0, 0)), {}, kDt, out);
    EXPECT_TRUE(near(out.body_target.position_m, expected_target(p), 1e-12)) << "sample " << i;
    EXPECT_NEAR(norm(sub(out.body_target.position_m, world_centre)), 5 * radius, 1e-12);
    // The device does not turn: the target keeps the location's orientation.
    EXPECT_NEAR(std::abs(out.body_target.orientation.z), std::sin(kPi / 4), 1e-12);
    EXPECT_NEAR(std::abs(out.body_target.orientation.w), std::cos(kPi / 4), 1e-12);
  }
}

TEST(TeleopLaw, TheBodyWrenchIsAPdOnTheTargetError) {
  TeleopLaw law(plain_params());
  TeleopOutput out;
  // First cycle: target at the location (origin); the body is 0.1 m off in x, moving
  // at 1 m/s in x, turned 0.1 rad about z and turning at 2 rad/s.
  Twist twist;
  twist.linear_mps = v3(1, 0, 0);
  twist.angular_radps = v3(0, 0, 2);
  const Pose body = pose_at(v3(0.1, 0, 0), about_z(0.1));
  law.step(device_at(v3(0, 0, 0)), body, twist, kDt, out);
  EXPECT_TRUE(near(out.body_wrench.force_n, v3(100 * -0.1 + 10 * -1.0, 0, 0), 1e-9));
  EXPECT_TRUE(near(out.body_wrench.torque_nm, v3(0, 0, 5 * -0.1 + 1 * -2.0), 1e-9));
  // The device moves 1 mm in x in 1 ms: the target 1 cm, at 10 m/s.
  law.step(device_at(v3(0.001, 0, 0)), body, twist, kDt, out);
  EXPECT_TRUE(near(out.body_target.position_m, v3(0.01, 0, 0), 1e-12));
  EXPECT_TRUE(
      near(out.body_wrench.force_n, v3(100 * (0.01 - 0.1) + 10 * (10.0 - 1.0), 0, 0), 1e-9));
}

TEST(TeleopLaw, TheTargetsVelocityIsTimedByTheDevicesSamplesNotTheCycles) {
  // The device moves at 1 cm/s in x (the target at 10 cm/s); the body sits on the target,
  // still, so the wrench is the D gain times the target's velocity.
  TeleopLaw law(plain_params());
  TeleopOutput out;
  const double speed = 0.01;
  auto sample = [&](std::int64_t ms) {
    DeviceState device = device_at(v3(speed * static_cast<double>(ms) * 1e-3, 0, 0));
    device.header.publish_stamp_ns = ms * 1'000'000;
    return device;
  };
  auto cycle = [&](std::int64_t ms, double dt_s) {
    const DeviceState device = sample(ms);
    law.step(device, pose_at(v3(10 * device.pose.position_m.x, 0, 0)), {}, dt_s, out);
    return out.body_wrench.force_n.x;
  };
  for (std::int64_t ms = 0; ms <= 10; ++ms) cycle(ms, kDt);  // anchored at x 0
  const double on_time = 10 * 10 * speed;                    // D 10 x 0.1 m/s
  EXPECT_NEAR(cycle(11, kDt), on_time, 1e-9);
  // Both loops stalled 17 ms and catch up back to back: teleop's cycles 10 us apart see
  // the driver's samples of its own catch-up (1 ms apart when it keeps its stamps' pace).
  EXPECT_NEAR(cycle(28, 0.017), on_time, 1e-9);
  for (std::int64_t ms = 29; ms <= 34; ++ms)
    EXPECT_NEAR(cycle(ms, 10e-6), on_time, 1e-9) << "sample at " << ms << " ms";
  // Cycles that find no new sample keep the velocity for one sample interval (the loops'
  // phases jitter), then assume no motion (a driver that stopped moves nothing); the next
  // sample gives the motion since.
  EXPECT_NEAR(cycle(34, 0.0005), on_time, 1e-9);
  EXPECT_NEAR(cycle(34, 0.0004), on_time, 1e-9);
  EXPECT_NEAR(cycle(34, 0.0002), 0.0, 1e-9);
  EXPECT_NEAR(cycle(36, kDt), on_time, 1e-9);
}

TEST(TeleopLaw, ClutchHoldsTheTargetAndReleasesWithoutAJump) {
  TeleopParams params = plain_params();
  TeleopLaw law(params);
  TeleopOutput out;
  const std::uint32_t clutch = 1U << params.buttons.clutch;
  const double step = 0.0002;  // device metres per cycle, along x, turning about z
  Vec3 previous{};
  Quaternion previous_rotation{};
  double largest_move = 0.0;
  double largest_turn = 0.0;
  Vec3 held{};
  for (int i = 0; i < 300; ++i) {
    const bool clutched = i >= 100 && i < 200;
    const Vec3 p = v3(step * i, 0, 0);
    law.step(device_at(p, clutched ? clutch : 0, about_z(0.002 * i)), pose_at(v3(0, 0, 0)), {}, kDt,
             out);
    EXPECT_EQ(out.clutched, clutched);
    if (i == 100) held = out.body_target.position_m;
    if (clutched) {
      // The body holds: the target stays where it was when the clutch closed, and the
      // device gets no force.
      EXPECT_TRUE(near(out.body_target.position_m, held, 1e-15)) << "cycle " << i;
      EXPECT_EQ(norm(out.device_wrench.force_n), 0.0);
    }
    if (i > 0) {
      largest_move = std::max(largest_move, norm(sub(out.body_target.position_m, previous)));
      const Quaternion& q = out.body_target.orientation;
      const double cosine = std::abs(q.x * previous_rotation.x + q.y * previous_rotation.y +
                                     q.z * previous_rotation.z + q.w * previous_rotation.w);
      largest_turn = std::max(largest_turn, 2 * std::acos(std::min(1.0, cosine)));
    }
    previous = out.body_target.position_m;
    previous_rotation = out.body_target.orientation;
  }
  // No jump anywhere: never more than the scaled device step in one cycle (the device
  // moved 100 steps while clutched), nor more than the device's turn per cycle.
  EXPECT_LE(largest_move, 10 * step + 1e-12);
  EXPECT_LE(largest_turn, 0.002 + 1e-9);
  // After release the target follows again, from where it held: 100 cycles of motion
  // before the clutch and 99 after release.
  EXPECT_TRUE(near(out.body_target.position_m, v3(10 * step * (99 + 99), 0, 0), 1e-12));
}

TEST(TeleopLaw, TheDeviceForceOpposesTheBodyToProxyDifferenceAndIsBounded) {
  TeleopParams params = plain_params();
  params.max_force_n = 2.0;
  params.location.orientation = about_z(kPi / 2);
  TeleopLaw law(params);
  TeleopOutput out;
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out);
  // Pushing into the floor: the device asks 5 cm (world) down, the floor keeps the body
  // at 0. The force pushes the hand back up, 10 N/m * 0.05 m = 0.5 N.
  law.step(device_at(v3(0, 0, -0.005)), pose_at(v3(0, 0, 0)), {}, kDt, out);
  EXPECT_TRUE(near(out.device_wrench.force_n, v3(0, 0, 0.5), 1e-12));
  // In the device's frame: the body 0.1 m along world x from the target is along device
  // -y (the location is turned 90 degrees about z).
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0.1, 0, 0)), {}, kDt, out);
  EXPECT_TRUE(near(out.device_wrench.force_n, v3(0, -1.0, 0), 1e-12));

  // Any offset: the force (turned back into the world) points from the proxy to the
  // body, and never exceeds the max force.
  std::mt19937 random(7);
  std::uniform_real_distribution<double> offset(-1.0, 1.0);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 body = v3(offset(random), offset(random), offset(random));
    law.step(device_at(v3(0, 0, 0)), pose_at(body), {}, kDt, out);
    const Vec3 f = out.device_wrench.force_n;
    const Vec3 world_force = v3(-f.y, f.x, f.z);
    EXPECT_LE(norm(f), 2.0 + 1e-12);
    EXPECT_GT(dot(world_force, body), 0.0);
    EXPECT_NEAR(norm(f), std::min(2.0, 10.0 * norm(body)), 1e-9);
  }
}

// --feedback contact: the device gets the body's contact force times haptic gain / P
// (10 / 100 here), in the device's frame, through the same limits; none with no contact
// whatever the lag. --feedback both: the sum of the two.
TEST(TeleopLaw, ContactFeedbackRendersTheBodysContactForce) {
  TeleopParams params = plain_params();
  params.max_force_n = 2.0;
  params.location.orientation = about_z(kPi / 2);
  params.feedback = FeedbackSource::kContact;
  TeleopLaw law(params);
  TeleopOutput out;
  const Wrench floor_push{v3(0, 0, 5.0), v3(0, 0, 0)};
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out, floor_push);
  EXPECT_TRUE(near(out.device_wrench.force_n, v3(0, 0, 0.5), 1e-12));
  // World x is device -y; and the 0.3 m lag gives nothing in contact mode.
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0.3, 0, 0)), {}, kDt, out,
           {v3(10.0, 0, 0), v3(0, 0, 0)});
  EXPECT_TRUE(near(out.device_wrench.force_n, v3(0, -1.0, 0), 1e-12));
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0.3, 0, 0)), {}, kDt, out);
  EXPECT_EQ(norm(out.device_wrench.force_n), 0.0);
  // Bounded by the max force.
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out,
           {v3(0, 0, 1000.0), v3(0, 0, 0)});
  EXPECT_TRUE(near(out.device_wrench.force_n, v3(0, 0, 2.0), 1e-12));
  // The torque alike: angular haptic gain 0.5 over angular P 5.
  params.haptic_gain_angular = 0.5;
  params.max_force_n = 0.0;
  TeleopLaw turning(params);
  turning.step(device_at(v3(0, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out,
               {v3(0, 0, 0), v3(0, 0, 2.0)});
  EXPECT_TRUE(near(out.device_wrench.torque_nm, v3(0, 0, 0.2), 1e-12));

  params.feedback = FeedbackSource::kBoth;
  params.location.orientation = {};
  TeleopLaw both(params);
  both.step(device_at(v3(0, 0, 0)), pose_at(v3(0.05, 0, 0)), {}, kDt, out,
            {v3(0, 0, 3.0), v3(0, 0, 0)});
  EXPECT_TRUE(near(out.device_wrench.force_n, v3(0.5, 0, 0.3), 1e-12));
  // The default, proxy, ignores contacts.
  params.feedback = FeedbackSource::kProxy;
  TeleopLaw proxy(params);
  proxy.step(device_at(v3(0, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out,
             {v3(0, 0, 3.0), v3(0, 0, 0)});
  EXPECT_EQ(norm(out.device_wrench.force_n), 0.0);
}

TEST(TeleopLaw, TheDevicesOwnLimitsApplyToo) {
  TeleopParams params = plain_params();
  params.max_force_n = 10.0;
  TeleopLaw law(params);
  DeviceState device = device_at(v3(0, 0, 0));
  device.spec.max_force_n = 3.0;
  device.spec.max_stiffness_npm = 50.0;  // / scale 10: at most 5 N/m of world distance
  TeleopOutput out;
  law.step(device, pose_at(v3(0.1, 0, 0)), {}, kDt, out);
  EXPECT_TRUE(near(out.device_wrench.force_n, v3(0.5, 0, 0), 1e-12));
  law.step(device, pose_at(v3(1.0, 0, 0)), {}, kDt, out);
  EXPECT_TRUE(near(out.device_wrench.force_n, v3(3.0, 0, 0), 1e-12));
}

TEST(TeleopLaw, DeadbandRendersNoSmallForceAndIsContinuousPastIt) {
  TeleopParams params = plain_params();
  params.deadband_n = 0.5;
  TeleopLaw law(params);
  TeleopOutput out;
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0.04, 0, 0)), {}, kDt, out);
  EXPECT_EQ(norm(out.device_wrench.force_n), 0.0);  // 0.4 N is inside the band
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0.0499, 0, 0)), {}, kDt, out);
  EXPECT_EQ(norm(out.device_wrench.force_n), 0.0);
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0.0501, 0, 0)), {}, kDt, out);
  EXPECT_NEAR(out.device_wrench.force_n.x, 0.001, 1e-12);  // just past: small, not 0.5
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0.1, 0, 0)), {}, kDt, out);
  EXPECT_NEAR(out.device_wrench.force_n.x, 0.5, 1e-12);
}

TEST(TeleopLaw, MaxJerkLimitsHowFastTheForceChanges) {
  TeleopParams params = plain_params();
  params.max_jerk_n_per_ms = 0.2;
  TeleopLaw law(params);
  TeleopOutput out;
  // The body suddenly 0.5 m off: 5 N wanted at once.
  double last = 0.0;
  int cycles = 0;
  for (; cycles < 100 && last < 5.0 - 1e-12; ++cycles) {
    law.step(device_at(v3(0, 0, 0)), pose_at(v3(0.5, 0, 0)), {}, kDt, out);
    const double now = out.device_wrench.force_n.x;
    EXPECT_LE(now - last, 0.2 + 1e-12) << "cycle " << cycles;
    last = now;
  }
  EXPECT_EQ(cycles, 25);  // 5 N at 0.2 N per millisecond
  // At half the step, half the change per cycle; and it comes down as gently.
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt / 2, out);
  EXPECT_NEAR(out.device_wrench.force_n.x, 4.9, 1e-12);
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0, 0, 0)), {}, 0.0, out);
  EXPECT_NEAR(out.device_wrench.force_n.x, 4.9, 1e-12);  // no time, no change
}

TEST(TeleopLaw, GripperFromTheButtonTheDeviceAngleOrTheJawMode) {
  TeleopParams params = plain_params();
  params.buttons.gripper = 4;
  TeleopLaw law(params);
  TeleopOutput out;
  law.step(device_at(v3(0, 0, 0)), {}, {}, kDt, out);
  EXPECT_EQ(out.gripper, 1.0);
  EXPECT_FALSE(out.grasp);
  law.step(device_at(v3(0, 0, 0), 1U << 4), {}, {}, kDt, out);
  EXPECT_EQ(out.gripper, 0.0);
  EXPECT_TRUE(out.grasp);
  EXPECT_FALSE(out.clutched);

  // A device that senses its gripper gives the angle, within [0, 1].
  DeviceState sensing = device_at(v3(0, 0, 0));
  sensing.spec.sensed = kDeviceTranslation | kDeviceGripper;
  sensing.gripper_angle_rad = 0.3;
  law.step(sensing, {}, {}, kDt, out);
  EXPECT_DOUBLE_EQ(out.gripper, 0.3);
  sensing.gripper_angle_rad = 1.7;
  law.step(sensing, {}, {}, kDt, out);
  EXPECT_DOUBLE_EQ(out.gripper, 1.0);

  // No gripper button: the jaw mode's a1 opens and a2 closes it by tenths, and a1 does
  // not clutch there. Next mode goes there, prev mode comes back.
  TeleopLaw jaw(plain_params());
  const ButtonMapping b;
  const std::uint32_t a1 = 1U << b.clutch, a2 = 1U << b.camera, next = 1U << b.next_mode,
                      prev = 1U << b.prev_mode;
  jaw.step(device_at(v3(0, 0, 0)), {}, {}, kDt, out);
  EXPECT_EQ(out.gripper, 0.5);
  EXPECT_EQ(out.mode, TeleopMode::kClutchCamera);
  jaw.step(device_at(v3(0, 0, 0), next), {}, {}, kDt, out);
  EXPECT_EQ(out.mode, TeleopMode::kGripperJaw);
  for (std::uint32_t buttons : {0U, a1, 0U, a1, 0U, a2}) {
    jaw.step(device_at(v3(0, 0, 0), buttons), {}, {}, kDt, out);
    EXPECT_FALSE(out.clutched);
  }
  EXPECT_NEAR(out.gripper, 0.6, 1e-12);
  jaw.step(device_at(v3(0, 0, 0), prev), {}, {}, kDt, out);
  EXPECT_EQ(out.mode, TeleopMode::kClutchCamera);
  jaw.step(device_at(v3(0, 0, 0), a2), {}, {}, kDt, out);
  EXPECT_TRUE(out.clutched);  // a2 moves the camera, and the body holds meanwhile
  EXPECT_TRUE(out.camera_held);
}

// hold(): a device whose samples went stale (its driver died). The target holds, the
// device gets no force, and when it is let go with the hand elsewhere (a new driver's
// hand at its start) the target continues from where it held.
TEST(TeleopLaw, HoldKeepsTheTargetAndLettingGoReanchorsWithoutAJump) {
  TeleopParams params = plain_params();
  params.buttons.clutch = -1;  // no clutch button: hold() alone holds
  TeleopLaw law(params);
  TeleopOutput out;
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out);
  law.step(device_at(v3(0.02, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out);
  const Vec3 held = out.body_target.position_m;
  EXPECT_GT(norm(out.device_wrench.force_n), 0.0);
  law.hold(true);
  law.step(device_at(v3(0.02, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out);
  EXPECT_TRUE(out.clutched);
  EXPECT_TRUE(near(out.body_target.position_m, held, 1e-15));
  EXPECT_EQ(norm(out.device_wrench.force_n), 0.0);
  law.hold(false);
  law.step(device_at(v3(-0.01, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out);
  EXPECT_TRUE(near(out.body_target.position_m, held, 1e-15)) << "a jump on letting go";
  law.step(device_at(v3(0.0, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out);
  EXPECT_NEAR(out.body_target.position_m.x, held.x + params.workspace_scale * 0.01, 1e-12);
}

// re_anchor(): a new driver's hand, elsewhere, with no stale gap between (a driver
// restarted at once): the target continues from where it was (it followed the 3 cm
// from the old hand to the new one, scaled: the body thrown 0.7 m in the end-to-end run).
TEST(TeleopLaw, ReanchoringTakesANewDriversHandWithoutAJump) {
  TeleopParams params = plain_params();
  TeleopLaw law(params);
  TeleopOutput out;
  law.step(device_at(v3(0, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out);
  law.step(device_at(v3(0.02, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out);
  const Vec3 before = out.body_target.position_m;
  law.re_anchor();
  law.step(device_at(v3(-0.01, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out);
  EXPECT_TRUE(near(out.body_target.position_m, before, 1e-15)) << "a jump to the new hand";
  law.step(device_at(v3(0.0, 0, 0)), pose_at(v3(0, 0, 0)), {}, kDt, out);
  EXPECT_NEAR(out.body_target.position_m.x, before.x + params.workspace_scale * 0.01, 1e-12);
}

// Re-anchored (a new driver) or restarted from the body's pose (teleop stood still),
// with the body held off the target: the device's force starts again from none and
// grows within the jerk limit (it was the old force, then ramped down).
TEST(TeleopLaw, ReanchoringOrRestartingStartsTheDeviceForceAgainFromNone) {
  for (const bool restart : {false, true}) {
    TeleopParams params = plain_params();
    params.max_jerk_n_per_ms = 0.2;
    TeleopLaw law(params);
    TeleopOutput out;
    // The body 0.2 m from the target: 2 N on the device once the ramp is done.
    for (int i = 0; i < 20; ++i)
      law.step(device_at(v3(0, 0, 0)), pose_at(v3(0.2, 0, 0)), {}, kDt, out);
    ASSERT_NEAR(out.device_wrench.force_n.x, 2.0, 1e-9);
    if (restart)
      law.restart_from(pose_at(v3(0.1, 0, 0)));
    else
      law.re_anchor();
    law.step(device_at(v3(0.05, 0, 0)), pose_at(v3(0.2, 0, 0)), {}, 0.0, out);
    EXPECT_EQ(out.device_wrench.force_n.x, 0.0) << (restart ? "restarted" : "re-anchored");
    law.step(device_at(v3(0.05, 0, 0)), pose_at(v3(0.2, 0, 0)), {}, kDt, out);
    EXPECT_NEAR(out.device_wrench.force_n.x, 0.2 * kDt * 1000.0, 1e-9)
        << (restart ? "restarted" : "re-anchored");
  }
}

TEST(TeleopLaw, RestartFromDrivesTheBodyFromWhereItIs) {
  TeleopLaw law(plain_params());
  TeleopOutput out;
  law.step(device_at(v3(0.02, 0, 0)), {}, {}, kDt, out);
  law.restart_from(pose_at(v3(1, 2, 3)));
  law.step(device_at(v3(0.05, 0, 0)), {}, {}, kDt, out);
  EXPECT_TRUE(near(out.body_target.position_m, v3(1, 2, 3), 1e-15));
  law.step(device_at(v3(0.06, 0, 0)), {}, {}, kDt, out);
  EXPECT_TRUE(near(out.body_target.position_m, v3(1.1, 2, 3), 1e-12));
}

TEST(TeleopLaw, ACycleAllocatesNothing) {
  TeleopParams params = plain_params();
  params.deadband_n = 0.01;
  params.max_force_n = 5.0;
  params.max_jerk_n_per_ms = 0.2;
  TeleopLaw law(params);
  TeleopOutput out;
  const long before = test::heap_allocations();
  for (int i = 0; i < 1000; ++i) {
    const double angle = 2 * kPi * i / 1000;
    law.step(device_at(v3(0.02 * std::cos(angle), 0.02 * std::sin(angle), 0),
                       (i / 100) % 2 ? 1U : 0U, about_z(angle)),
             pose_at(v3(0.1, 0, 0), about_z(-angle)), {}, kDt, out);
  }
  EXPECT_EQ(test::heap_allocations() - before, 0);
}

}  // namespace
}  // namespace afhub::teleop
