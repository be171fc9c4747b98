// Teleoperation end to end with AMBF's own files, read in place from ../shared: the
// input device file's "Novint Falcon1" (-d 5: hardware name Falcon, so device/falcon;
// workspace scaling 10; location (0, 0.5, 0); haptic gain 0.5 N/m, deadband 0.01 N,
// max force 10 N; a1 = button 0 clutches) driving the PR2 gripper it names, whose palm
// (r_gripper_palm_link) is the root body, with its own controller gains (P 200 N/m,
// no "controller gain" in the device entry). The virtual device is run as the
// hardware it stands for: `afhub device run virtual --name falcon`.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "real_time.hpp"
#include "shared_models.hpp"
#include "teleop_session.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

const std::string kDevicesFile =
    AFHUB_SHARED_MODELS "/descriptions/input_devices/input_devices.yaml";
const std::string kGripper =
    AFHUB_SHARED_MODELS "/descriptions/multi-bodies/grippers/pr2 gripper.yaml";
const std::string kPalm = "ambf/env/r_gripper_palm_link";
// From the device entry.
constexpr double kScale = 10.0;
constexpr double kLx = 0.0, kLy = 0.5, kLz = 0.0;
constexpr double kHapticGain = 0.5, kDeadband = 0.01, kMaxForce = 10.0;
// From the gripper: its five bodies' masses and the palm's linear P gain. The PD holds
// the gripper's weight m g with the palm m g / P below its target.
constexpr double kMassKg = 0.58 + 0.171 + 0.044 + 0.174 + 0.044;
constexpr double kSag = kMassKg * 9.81 / 200.0;  // 0.0497 m

// The gripper (and `extra` models), device 5 of the file, a virtual "falcon".
TeleopSetup pr2_setup(const afhub::testing::ModelFolder& folder,
                      const std::vector<std::string>& driver_args,
                      const std::vector<std::string>& extra = {}) {
  TeleopSetup s;
  s.models = {kGripper};
  s.models.insert(s.models.end(), extra.begin(), extra.end());
  s.devices_file = kDevicesFile;
  s.teleop_args = {"-d", "5"};
  s.body = kPalm;
  s.device = "falcon";
  s.driver_args = driver_args;
  s.log = (folder.dir() / "log").string();
  return s;
}

// The device's circle, 2 cm in 4 s, is a 20 cm circle of the palm. Teleop anchors on
// the device's first sample, so the palm's path is expected at
//   location + 10 (device(t) - anchor) - (0, 0, m g / P)
// with the anchor a point of the device's circle: the palm's circle passes through
// the location, 5 cm lower.
TEST(TeleopPr2, ThePalmFollowsTheFalconsCircleScaledFromTheLocation) {
  SKIP_WITHOUT_SHARED_MODELS();
  afhub::testing::ModelFolder folder;
  TeleopSession teleop(pr2_setup(folder, {"--circle", "0.02,4"}));
  ASSERT_TRUE(teleop.wait_running()) << teleop.logs();
  pause_ms(2000);  // past the force ramp and the start transient
  const Following f = measure_following(teleop, kScale, 2000);  // about a turn
  // The anchor that fits: location + 10 (device - anchor) - sag = body, on average.
  const double ax = f.device_mean.x - (f.body_mean.x - kLx) / kScale;
  const double ay = f.device_mean.y - (f.body_mean.y - kLy) / kScale;
  const double az = f.device_mean.z - (f.body_mean.z - (kLz - kSag)) / kScale;
  std::printf(
      "pr2 circle: palm radius %.4f m (device's x10: 0.2 m), anchor (%.4f, %.4f, %.4f) m "
      "(%.4f m from the device circle's centre), deviation median %.4f m, RMS %.4f m, worst "
      "%.4f m\n",
      f.body_radius, ax, ay, az, std::hypot(ax, ay), f.median, f.rms, f.worst);
  SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD();
  ASSERT_GE(f.judged, 1000) << "the machine was too busy to judge the following: the physics "
                               "or the driver kept missing its period\n"
                            << teleop.logs();
  EXPECT_NEAR(f.body_radius, 0.2, 0.02) << teleop.logs();
  // The anchor is a point of the device's path (its 2 cm circle at height 0): the palm's
  // path is the location plus the scaled device's motion from there, 5 cm lower.
  EXPECT_NEAR(std::hypot(ax, ay), 0.02, 0.002) << "the palm's circle misses the location";
  EXPECT_NEAR(az, 0.0, 0.001) << "the palm's height is not the location's less the sag";
  // Bound: 1 cm median, for a palm moving at 0.31 m/s (measured 2.8 mm, worst 3.3 mm, at
  // load 8: the PD's lag and the test's two reads of the channels). RMS and worst are
  // printed only: on a machine this loaded (load 9 on 2 cores) a process that does not
  // run for a while gives outliers of centimetres.
  EXPECT_LT(f.median, 0.01) << teleop.logs();
}

// a1 (button 0) clutches: the palm stays while the hand goes back, and moves on from
// there with no jump when it is let go.
TEST(TeleopPr2, ClutchHoldsThePalmAndReleasingItGivesNoJump) {
  SKIP_WITHOUT_SHARED_MODELS();
  afhub::testing::ModelFolder folder;
  const std::string csv = folder.write("clutch.csv", kClutchTrajectory);
  TeleopSession teleop(pr2_setup(folder, {"--trajectory", csv}));
  ASSERT_TRUE(teleop.wait_running()) << teleop.logs();
  ClutchRun run;
  ASSERT_TRUE(run_clutch(teleop, run)) << teleop.logs();
  std::printf("pr2 clutch: drift while held %.2e m, largest move after release %.2e m\n",
              run.held_drift, run.jump);
  SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD();
  EXPECT_NEAR(run.before_clutch, kLx + kScale * 0.02, 0.01) << teleop.logs();
  EXPECT_LT(run.held_drift, 0.005) << "the palm moved while clutched";
  // Without re-anchoring the palm would go 20 cm back.
  EXPECT_LT(run.jump, 0.005) << teleop.logs();
  EXPECT_NEAR(run.after, run.released + kScale * 0.01, 0.01) << teleop.logs();
}

// A floor (the test's own, top at z = -0.7 m: the gripper's file starts it at z = -0.5)
// under the gripper. The hand goes 15 cm down, the proxy 1.5 m, about 0.8 m under the
// palm resting on the floor: the device gets the haptic gain times that, less the
// deadband, upward (about 0.4 N), never more than the max force; the palm stays on the
// floor.
TEST(TeleopPr2, PushingThePalmIntoTheFloorGivesAnOpposingBoundedForce) {
  SKIP_WITHOUT_SHARED_MODELS();
  afhub::testing::ModelFolder folder;
  constexpr double kFloorTop = -0.7;
  const std::string floor = folder.write("floor.yaml",
                                         "bodies: [BODY floor]\n"
                                         "joints: []\n"
                                         "namespace: /test/env/\n"
                                         "BODY floor:\n"
                                         "  name: floor\n"
                                         "  mass: 0.0\n"
                                         "  location: {position: {x: 0, y: 0, z: -0.75}, "
                                         "orientation: {r: 0, p: 0, y: 0}}\n"
                                         "  shape: BOX\n"
                                         "  geometry: {x: 4.0, y: 4.0, z: 0.1}\n"
                                         "  collision shape: BOX\n"
                                         "  collision geometry: {x: 4.0, y: 4.0, z: 0.1}\n"
                                         "  collision margin: 0.001\n"
                                         "  passive: true\n");
  const std::string csv = folder.write("push.csv", "0,0,0,0\n1,0,0,0\n3,0,0,-0.15\n8,0,0,-0.15\n");
  TeleopSession teleop(pr2_setup(folder, {"--trajectory", csv}, {floor}));
  ASSERT_TRUE(teleop.wait_running()) << teleop.logs();
  double most_force = 0.0, lowest_palm = 1.0, up_force_sum = 0.0, expected_sum = 0.0;
  int pressing = 0;
  for (int i = 0; i < 2500; ++i) {  // about 5 s, every 2 ms
    const DeviceState& device = teleop.device();
    const Vec3& f = device.applied.force_n;
    const double palm_z = teleop.body().pose.position_m.z;
    most_force = std::max(most_force, std::sqrt(f.x * f.x + f.y * f.y + f.z * f.z));
    lowest_palm = std::min(lowest_palm, palm_z);
    if (device.pose.position_m.z < -0.13) {  // the palm is on the floor, the hand pushes on
      up_force_sum += f.z;
      // The proxy's height: the location plus 10 times the hand's drop from its start.
      const double proxy_z = kLz + kScale * device.pose.position_m.z;
      expected_sum += kHapticGain * (palm_z - proxy_z) - kDeadband;
      ++pressing;
    }
    pause_ms(2);
  }
  const double mean_up = pressing ? up_force_sum / pressing : 0.0;
  const double expected_up = pressing ? expected_sum / pressing : 0.0;
  std::printf(
      "pr2 push: palm lowest at z %.4f m (floor top %.2f), mean force up %.3f N while pressing "
      "(expected %.3f N, %d samples), largest force %.3f N (max force %.1f N)\n",
      lowest_palm, kFloorTop, mean_up, expected_up, pressing, most_force, kMaxForce);
  ASSERT_GT(pressing, 100) << "the hand never pushed down" << teleop.logs();
  EXPECT_LE(most_force, kMaxForce + 1e-9) << "the device got more than the max force";
  EXPECT_GT(lowest_palm, kFloorTop) << "the palm went through the floor";
  SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD();
  EXPECT_GT(mean_up, 0.2) << "the device got no force opposing the push";
  // (Measured 0.36 N for 0.40 N: the anchor is taken as the hand's start, z = 0.)
  EXPECT_NEAR(mean_up, expected_up, 0.2 * expected_up) << "not the haptic gain's force";
}

}  // namespace
}  // namespace afhub::test
