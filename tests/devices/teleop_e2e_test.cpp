// Teleoperation end to end, with no hardware: a hub, `afhub run` of the project's own
// gripper (examples/models/gripper.yaml, its palm the root body) and the floor,
// `afhub device run virtual` following a scripted trajectory, and `afhub teleop`
// binding the two. The device's motion is followed by the palm, scaled; the clutch
// holds the palm and lets go with no jump; pushing the palm into the floor gives an
// opposing force on the device, bounded by the file's max force, from the proxy or (with
// --feedback contact) from the contact force on the whole gripper: a finger pressed
// on a wall, the palm touching nothing, pushes the device back too.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <thread>
#include <vector>

#include "afhub/hub/hub_files.hpp"
#include "afhub/rt/percentile.hpp"
#include "real_time.hpp"
#include "teleop_session.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

const std::string kGripper = AFHUB_EXAMPLE_MODELS "/gripper.yaml";
const std::string kFloor = AFHUB_EXAMPLE_MODELS "/floor.yaml";
constexpr double kScale = 5.0;
constexpr double kMaxForce = 3.0;
// The palm's start, and the device frame's place in the world.
constexpr double kX0 = 0.6, kY0 = 0.8, kZ0 = 0.6;

// The shipped input devices file of the virtual device (examples/models/virtual_hand.yaml):
// the tests bind it to drivers of their own names with --device.
const std::string kVirtualHand = AFHUB_EXAMPLE_MODELS "/virtual_hand.yaml";

// Teleoperation that holds the palm only after 0.5 s without device samples.
const std::vector<std::string> kPatientTeleop = {"--stale", "500"};

// The project's gripper and the floor under `afhub teleop` with the virtual device
// named `device` following the driver arguments given.
class Teleop : public TeleopSession {
 public:
  Teleop(const std::string& device, const std::vector<std::string>& driver_args,
         const std::vector<std::string>& teleop_extra = {},
         const std::vector<std::string>& extra_models = {})
      : TeleopSession(setup(device, driver_args, teleop_extra, extra_models)) {}
  const BodyState& palm() { return body(); }

 private:
  static TeleopSetup setup(const std::string& device, const std::vector<std::string>& driver_args,
                           const std::vector<std::string>& teleop_extra,
                           const std::vector<std::string>& extra_models) {
    static afhub::testing::ModelFolder folder;
    TeleopSetup s;
    s.models = {kGripper, kFloor};
    s.models.insert(s.models.end(), extra_models.begin(), extra_models.end());
    s.devices_file = kVirtualHand;
    s.teleop_args = {"--device", device};
    s.teleop_args.insert(s.teleop_args.end(), teleop_extra.begin(), teleop_extra.end());
    s.body = "afhub/gripper/palm";
    s.device = device;
    s.driver_args = driver_args;
    s.log = (folder.dir() / ("log-" + device)).string();
    return s;
  }
};

TEST(TeleopEndToEnd, TheGripperFollowsTheDevicesCircleScaled) {
  // 2 cm, 2 s: 10 cm in the world. A driver descheduled for over 50 ms on a busy machine
  // would have the palm held and re-anchored (tested below): not this test's case.
  Teleop teleop("circle", {"--circle", "0.02,2"}, kPatientTeleop);
  ASSERT_TRUE(teleop.wait_running()) << teleop.logs();
  pause_ms(2000);  // past the force ramp and the start transient
  // The physics' count of the palm's steps under command, and of those whose command
  // answered the state it had just published.
  const std::uint32_t commanded = teleop.palm().commanded_steps;
  const std::uint32_t answered = teleop.palm().answered_steps;
  const Following f = measure_following(teleop, kScale, 2000);  // about four turns
  const double in_time = static_cast<double>(teleop.palm().answered_steps - answered) /
                         std::max(1U, teleop.palm().commanded_steps - commanded);
  // Each loop's wake-ups and overruns, to tell a stalled teleop, driver or physics apart
  // when the following fails (twice in CI, every state read fresh: RMS 21 mm, p99 105 mm;
  // RMS 5.2 mm, p99 32 mm with loops woken 17 ms late: teleop's catch-up kicks, tested
  // by stalling the three below).
  const std::string loops = run_afhub({"top", "--once"}).out;
  const Vec3& body_mean = f.body_mean;
  const double radius = f.body_radius, rms = f.rms, worst = f.worst;
  std::printf(
      "circle: palm radius %.4f m (device's x5: 0.1 m), deviation RMS %.4f m, p99 %.4f m, "
      "worst %.4f m; %d pairs judged, %d left out (stalest state read %.1f ms old); "
      "%.1f %% of the palm's commands in time for the next step\n",
      radius, rms, f.p99, worst, f.judged, f.left_out, f.stalest_ms, 100 * in_time);
  SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD();
  // Teleop wakes in phase with the physics (half a period after each step is due):
  // misses come from this machine's stalls (the controllers' bound).
  EXPECT_GT(in_time, 0.75) << teleop.logs();
  ASSERT_GE(f.judged, 1000) << "the machine was too busy to judge the following: the physics "
                               "or the driver kept missing its period\n"
                            << teleop.logs();
  // The palm goes round a 10 cm circle, as the device does x5, in the location's plane
  // (its centre is where the device's was, relative to its first sample)...
  EXPECT_NEAR(radius, 0.1, 0.01) << teleop.logs();
  EXPECT_NEAR(body_mean.z, kZ0, 0.005);
  EXPECT_LT(std::hypot(body_mean.x - kX0, body_mean.y - kY0), 0.1 + 0.01);
  // ... and where the scaled device was: within 5 mm RMS and 1.5 cm at p99 (measured:
  // RMS 1.6 to 2.2 mm, worst 1.9 to 4.3 mm; at load 10 a worst of 10.7 mm once, so
  // the bound is on p99, the worst printed; in a CI run on the loaded 2-core machine
  // once RMS 3.2 mm and p99 10.1 mm). It is the palm's lag behind a proxy moving at
  // 0.31 m/s and the test's two reads of the channels, which a busy machine can delay;
  // before the reads were judged on the states' stamps, a physics descheduled for
  // 76 ms at load 10 gave 7.8 mm RMS and 3.8 cm at worst. Not following at all is the
  // circle's 10 cm.
  EXPECT_LT(rms, 0.005) << teleop.logs() << "\nloops:\n" << loops;
  EXPECT_LT(f.p99, 0.015) << teleop.logs() << "\nloops:\n" << loops;
}

TEST(TeleopEndToEnd, TheGripperFollowsThroughStallsOfTheWholeMachine) {
  // A loaded VM stalls every process at once (CI: loops woken up to 17 ms late), and each
  // loop then catches up, back to back. Here the three are stopped together for 12 ms
  // every 100 ms: short of the 20 ms that measure_following leaves out as a stale state.
  // Before teleop timed the target's velocity by the device's samples, its catch-up
  // cycles microseconds apart made a kick of each sample's motion.
  Teleop teleop("stalled", {"--circle", "0.02,2"}, kPatientTeleop);
  ASSERT_TRUE(teleop.wait_running()) << teleop.logs();
  pause_ms(2000);
  std::atomic<bool> measuring{true};
  int stalls = 0;
  std::thread stall([&] {
    while (measuring) {
      teleop.signal_all(SIGSTOP);
      pause_ms(12);
      teleop.signal_all(SIGCONT);
      ++stalls;
      pause_ms(100);
    }
  });
  const std::uint32_t commanded = teleop.palm().commanded_steps;
  const std::uint32_t answered = teleop.palm().answered_steps;
  const Following f = measure_following(teleop, kScale, 2000);
  measuring = false;
  stall.join();
  const double in_time = static_cast<double>(teleop.palm().answered_steps - answered) /
                         std::max(1U, teleop.palm().commanded_steps - commanded);
  std::printf(
      "stalls: %d of 12 ms; palm radius %.4f m, deviation RMS %.4f m, p99 %.4f m, worst %.4f m; "
      "%d pairs judged, %d left out (stalest state read %.1f ms old); %.1f %% of the palm's "
      "commands in time for the next step\n",
      stalls, f.body_radius, f.rms, f.p99, f.worst, f.judged, f.left_out, f.stalest_ms,
      100 * in_time);
  SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD();
  ASSERT_GE(f.judged, 1000) << "the machine was too busy to judge the following\n" << teleop.logs();
  // The palm lags the device by a stall (12 ms at 0.31 m/s: 4 mm) and catches up
  // (measured: RMS 1.9 mm, p99 4.6 mm; before, RMS 47 mm, p99 26 cm).
  EXPECT_NEAR(f.body_radius, 0.1, 0.01) << teleop.logs();
  EXPECT_LT(f.rms, 0.005) << teleop.logs();
  EXPECT_LT(f.p99, 0.015) << teleop.logs();
}

TEST(TeleopEndToEnd, ClutchHoldsTheGripperAndReleasingItGivesNoJump) {
  afhub::testing::ModelFolder scripts;
  const std::string csv = scripts.write("clutch.csv", kClutchTrajectory);
  Teleop teleop("clutch", {"--trajectory", csv}, kPatientTeleop);
  ASSERT_TRUE(teleop.wait_running()) << teleop.logs();
  ClutchRun run;
  ASSERT_TRUE(run_clutch(teleop, run)) << teleop.logs();
  std::printf("clutch: drift while held %.2e m, largest move after release %.2e m\n",
              run.held_drift, run.jump);
  SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD();
  EXPECT_NEAR(run.before_clutch, kX0 + kScale * 0.02, 0.01) << teleop.logs();
  // While held, the hand goes back 2 cm: the palm stays.
  EXPECT_LT(run.held_drift, 0.005) << "the palm moved while clutched";
  EXPECT_LT(run.hand_at_release, 0.003) << "the hand came back while clutched";
  // Released with the hand 2 cm from where it was clutched: no jump (without
  // re-anchoring, the palm would go 10 cm back); motion resumes from there: the hand's
  // next 1 cm is 5 cm of palm.
  EXPECT_LT(run.jump, 0.005) << teleop.logs();
  EXPECT_NEAR(run.after, run.released + kScale * 0.01, 0.006) << teleop.logs();
}

TEST(TeleopEndToEnd, PushingIntoTheFloorGivesAnOpposingBoundedForce) {
  afhub::testing::ModelFolder scripts;
  // Down 20 cm: the proxy goes 1 m down, 40 cm below the floor's top (z 0).
  const std::string csv = scripts.write("push.csv", "0,0,0,0\n1,0,0,0\n3,0,0,-0.2\n8,0,0,-0.2\n");
  Teleop teleop("push", {"--trajectory", csv}, kPatientTeleop);
  ASSERT_TRUE(teleop.wait_running()) << teleop.logs();
  double most_force = 0.0, lowest_palm = 1.0, up_force_sum = 0.0;
  int pressing = 0;
  for (int i = 0; i < 2500; ++i) {  // about 5 s, every 2 ms
    const DeviceState& device = teleop.device();
    const Vec3& f = device.applied.force_n;
    most_force = std::max(most_force, std::sqrt(f.x * f.x + f.y * f.y + f.z * f.z));
    lowest_palm = std::min(lowest_palm, teleop.palm().pose.position_m.z);
    // The palm is on the floor and the hand pushes on, with the teleoperation's commands
    // arriving (on a busy machine a late one has the driver's watchdog zero the force).
    if (device.pose.position_m.z < -0.15 && device.gate == ForceGate::kApplying) {
      up_force_sum += f.z;
      ++pressing;
    }
    pause_ms(2);
  }
  const double mean_up = pressing ? up_force_sum / pressing : 0.0;
  std::printf(
      "push: palm lowest at z %.4f m, mean force up %.3f N while pressing (%d samples), "
      "largest force %.3f N (max force %.1f N)\n",
      lowest_palm, mean_up, pressing, most_force, kMaxForce);
  ASSERT_GT(pressing, 100) << "the hand never pushed down with the teleoperation commanding"
                           << teleop.logs();
  EXPECT_LE(most_force, kMaxForce + 1e-9) << "the device got more than the max force";
  EXPECT_GT(lowest_palm, 0.015) << "the palm went through the floor";
  SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD();
  EXPECT_GT(mean_up, 0.8 * kMaxForce) << "the device got no force opposing the push";
}

// The palm's largest move along x from `x` over `reads` reads 2 ms apart.
double largest_palm_move(Teleop& teleop, double x, int reads) {
  double largest = 0.0;
  for (int i = 0; i < reads; ++i) {
    largest = std::max(largest, std::abs(teleop.palm().pose.position_m.x - x));
    pause_ms(2);
  }
  return largest;
}

// The driver SIGKILLed with the palm 10 cm out: teleop says so once, holds the palm
// where it is, and when a new driver publishes (its hand back at the trajectory's
// start, 2 cm from where the old one was) the palm continues from where it was held,
// with no jump (without re-anchoring it would go 10 cm back), and follows again.
TEST(TeleopEndToEnd, WhenTheDriverDiesThePalmIsHeldAndResumesWithNoJump) {
  afhub::testing::ModelFolder scripts;
  // Still for 1 s, out 2 cm in 1 s, then still.
  const std::string csv = scripts.write("out.csv", "0,0,0,0\n1,0,0,0\n2,0.02,0,0\n");
  Teleop teleop("dies", {"--trajectory", csv});
  ASSERT_TRUE(teleop.wait_running()) << teleop.logs();
  ASSERT_TRUE(wait_until([&] { return teleop.device().pose.position_m.x > 0.0195; }, 20s));
  pause_ms(500);
  const double out = teleop.palm().pose.position_m.x;
  EXPECT_NEAR(out, kX0 + kScale * 0.02, 0.01) << teleop.logs();
  const char* said = "no sample from device/dies";
  // Said once for this outage. (A driver starved for 50 ms before the kill, as a
  // sanitizer run beside other tests once did, has been said already: not counted.)
  const int said_before = occurrences(teleop.teleop_log(), said);
  const std::int64_t killed_at = monotonic_ns();
  teleop.kill_driver();
  ASSERT_TRUE(wait_until([&] { return occurrences(teleop.teleop_log(), said) > said_before; }, 5s))
      << teleop.logs();
  const double held_drift = largest_palm_move(teleop, out, 250);
  EXPECT_LT(held_drift, 0.005) << "the palm moved while the device was gone";
  EXPECT_EQ(occurrences(teleop.teleop_log(), said), said_before + 1) << teleop.teleop_log();

  teleop.start_driver();  // its hand at x = 0 for 1 s
  ASSERT_TRUE(wait_until([&] { return teleop.device().header.publish_stamp_ns > killed_at; }, 20s));
  const double jump = largest_palm_move(teleop, out, 300);  // while the new hand stays at 0
  std::printf(
      "driver killed: palm drift while held %.2e m, largest move after it came back %.2e m\n",
      held_drift, jump);
  EXPECT_TRUE(contains(teleop.teleop_log(), "device/dies is back")) << teleop.teleop_log();
  SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD();
  EXPECT_LT(jump, 0.005) << "the palm jumped when the device came back" << teleop.logs();
  // Motion resumes from there: the new hand's 2 cm are 10 cm more of palm.
  ASSERT_TRUE(wait_until([&] { return teleop.device().pose.position_m.x > 0.0195; }, 20s));
  pause_ms(500);
  EXPECT_NEAR(teleop.palm().pose.position_m.x, out + kScale * 0.02, 0.01) << teleop.logs();
}

// The driver SIGKILLed and started again at once, within teleop's stale time (here
// 2 s): no stale gap is seen, and the new driver's hand, 2 cm from the old one, was
// taken as a move of the hand (the palm thrown 0.7 m in a fault-injection run). Teleop
// sees the new driver, says so, and re-anchors: the palm does not jump.
TEST(TeleopEndToEnd, ADriverRestartedAtOnceIsReanchoredWithNoJump) {
  afhub::testing::ModelFolder scripts;
  const std::string csv = scripts.write("out.csv", "0,0,0,0\n1,0,0,0\n2,0.02,0,0\n");
  Teleop teleop("again", {"--trajectory", csv}, {"--stale", "2000"});
  ASSERT_TRUE(teleop.wait_running()) << teleop.logs();
  ASSERT_TRUE(wait_until([&] { return teleop.device().pose.position_m.x > 0.0195; }, 20s));
  pause_ms(500);
  const double out = teleop.palm().pose.position_m.x;
  const std::int64_t killed_at = monotonic_ns();
  teleop.kill_driver();
  teleop.start_driver();  // its hand at x = 0 for 1 s
  ASSERT_TRUE(wait_until([&] { return teleop.device().header.publish_stamp_ns > killed_at; }, 20s));
  const double jump = largest_palm_move(teleop, out, 300);  // while the new hand stays at 0
  std::printf("driver restarted at once: largest move of the palm after it %.2e m\n", jump);
  EXPECT_TRUE(contains(teleop.teleop_log(), "device/again has a new driver"))
      << teleop.teleop_log();
  EXPECT_FALSE(contains(teleop.teleop_log(), "no sample from device/again")) << teleop.logs();
  SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD();
  EXPECT_LT(jump, 0.005) << "the palm jumped to the new driver's hand" << teleop.logs();
}

// Teleop itself stopped (SIGSTOP) while the hand moves 2 cm: the driver takes the force
// off and the physics lets the palm go. Resumed, teleop says so and drives the palm on
// from where it is: no jump, the device does not pull the hand back, the force is on
// again, and the hand's next 2 cm are 10 cm more of palm. Before, the palm was pulled to
// the moved hand's place (10 cm at the scale of 5) and the device pulled the hand.
TEST(TeleopEndToEnd, ATeleopStoppedWhileTheHandMovesResumesWithNoJump) {
  afhub::testing::ModelFolder scripts;
  // Still for 3 s, out 2 cm in 1 s, still, out 2 cm more from 6 s to 7 s.
  const std::string csv =
      scripts.write("out.csv", "0,0,0,0\n3,0,0,0\n4,0.02,0,0\n6,0.02,0,0\n7,0.04,0,0\n");
  Teleop teleop("standstill", {"--trajectory", csv});
  ASSERT_TRUE(teleop.wait_running()) << teleop.logs();
  pause_ms(300);
  const double out = teleop.palm().pose.position_m.x;
  teleop.signal_teleop(SIGSTOP);
  ASSERT_LT(teleop.device().pose.position_m.x, 0.001) << "the hand moved before teleop stopped";
  ASSERT_TRUE(wait_until([&] { return teleop.device().pose.position_m.x > 0.0195; }, 20s));
  teleop.signal_teleop(SIGCONT);
  ASSERT_TRUE(wait_until(
      [&] { return contains(teleop.teleop_log(), "this process stood still for"); }, 10s))
      << teleop.logs();
  double jump = 0.0, force = 0.0;
  for (int i = 0; i < 300; ++i) {
    jump = std::max(jump, std::abs(teleop.palm().pose.position_m.x - out));
    const Vec3& f = teleop.device().applied.force_n;
    force = std::max(force, std::hypot(f.x, f.y, f.z));
    pause_ms(2);
  }
  const double resumed = teleop.palm().pose.position_m.x;
  EXPECT_TRUE(wait_until([&] { return teleop.device().gate == ForceGate::kApplying; }, 10s))
      << "the force stayed off" << teleop.logs();
  ASSERT_TRUE(wait_until([&] { return teleop.device().pose.position_m.x > 0.0395; }, 20s));
  pause_ms(500);
  const double followed = teleop.palm().pose.position_m.x - resumed;
  std::printf(
      "teleop stopped while the hand moved 2 cm: largest move of the palm after it %.2e m, "
      "largest force on the device %.3f N; the next 2 cm of hand %.4f m of palm\n",
      jump, force, followed);
  SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD();
  // Measured: 3.3 to 3.9 mm (the palm let go meanwhile) and 0.007 N; without the change
  // 0.100 m and 0.318 N.
  EXPECT_LT(jump, 0.01) << "the palm jumped to the moved hand" << teleop.logs();
  EXPECT_LT(force, 0.1) << "the device pulled the hand back" << teleop.logs();
  EXPECT_NEAR(followed, kScale * 0.02, 0.01) << "the palm did not follow again" << teleop.logs();
}

// A second teleop on the same device was taken: it anchored at the hand's pose while
// the first held the palm in the floor, and the two pulled the palm between them with
// the device at its maximum force. It is refused, naming the first.
TEST(TeleopEndToEnd, ASecondTeleopOnADeviceIsRefused) {
  Teleop teleop("twice", {});
  ASSERT_TRUE(teleop.wait_running()) << teleop.logs();
  const RunResult second = run_afhub(teleop.teleop_args(), 20s);
  EXPECT_EQ(second.exit_code, 1) << second.err;
  EXPECT_TRUE(contains(
      second.err, "device/twice is teleoperated by pid " + std::to_string(teleop.teleop_pid())))
      << second.err;
  EXPECT_TRUE(contains(second.err, "a device takes one teleoperation")) << second.err;
  EXPECT_FALSE(contains(second.err, "stopped")) << second.err;

  // The first stopped (a debugger, SIGSTOP): still refused, for it goes on once resumed,
  // and said stopped (it was named as if running).
  teleop.signal_teleop(SIGSTOP);
  const RunResult while_stopped = run_afhub(teleop.teleop_args(), 20s);
  teleop.signal_teleop(SIGCONT);
  EXPECT_EQ(while_stopped.exit_code, 1) << while_stopped.err;
  EXPECT_TRUE(contains(while_stopped.err, "pid " + std::to_string(teleop.teleop_pid()) +
                                              " (afhub teleop, stopped: SIGSTOP or a debugger"))
      << while_stopped.err;
}

// Two teleops started at the same moment both passed the look at the device's
// commands (neither commanded it yet), and fought over it. Both wait for the same body
// and device, so they reach the device together; its claim lets one through.
TEST(TeleopEndToEnd, OfTwoTeleopsStartedAtOnceOneIsRefused) {
  Teleop teleop("atonce", {});
  const std::string second_log = teleop.log_prefix() + ".second-teleop";
  ScopedProcess second(spawn_afhub(teleop.teleop_args(), second_log));
  ASSERT_TRUE(teleop.wait_running()) << teleop.logs();
  const std::string refused = "a device takes one teleoperation";
  ASSERT_TRUE(wait_until(
      [&] {
        return contains(teleop.teleop_log(), refused) || contains(read_file(second_log), refused);
      },
      10s))
      << "neither teleop was refused\n"
      << teleop.logs() << "\nsecond: " << read_file(second_log);
  EXPECT_NE(contains(teleop.teleop_log(), refused), contains(read_file(second_log), refused))
      << teleop.logs() << "\nsecond: " << read_file(second_log);
  pause_ms(500);  // the one let through goes on teleoperating
  EXPECT_TRUE(teleop.wait_running()) << teleop.logs();
}

// Something planted where the device's claim goes (here a FIFO): a teleop that could
// not take the claim could not refuse a second one started with it. It refuses to
// start, naming the path, and the device never gets a force.
TEST(TeleopEndToEnd, ATeleopThatCannotClaimItsDeviceDoesNotStart) {
  const std::string claims = hub_directory() + "/claims";
  mkdir(claims.c_str(), 0755);
  const std::string planted = claims + "/teleop.device.planted";
  ASSERT_EQ(mkfifo(planted.c_str(), 0644), 0) << std::strerror(errno);
  Teleop teleop("planted", {});
  const std::string refused = "cannot claim device/planted for this teleop (" + planted;
  EXPECT_TRUE(wait_until([&] { return contains(teleop.teleop_log(), refused); }, 20s))
      << teleop.logs();
  bool pushed = false;
  int states = 0;
  for (int i = 0; i < 250; ++i) {  // 0.5 s
    if (const DeviceState* d = teleop.new_device_state()) {
      pushed |= d->gate == ForceGate::kApplying;
      ++states;
    }
    pause_ms(2);
  }
  EXPECT_GT(states, 50) << "the driver published no states" << teleop.logs();
  EXPECT_FALSE(pushed) << teleop.logs();
  unlink(planted.c_str());
}

// Ctrl-C while teleop waits for its device's driver ends it with 0, as every other
// wait (it exited 1).
TEST(TeleopEndToEnd, CtrlCWhileWaitingForTheDeviceEndsWithZero) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "teleop.log").string();
  ScopedProcess physics(spawn_afhub({"run", kGripper, "--no-autostart"}, log + ".run"));
  ScopedProcess teleop(
      spawn_afhub({"teleop", kVirtualHand, "--device", "absent", "--wait", "30"}, log));
  ASSERT_TRUE(
      wait_until([&] { return contains(read_file(log), "waiting for device/absent"); }, 20s))
      << read_file(log) << read_file(log + ".run");
  EXPECT_EQ(teleop.stop(SIGINT), 0) << read_file(log);
  EXPECT_TRUE(contains(read_file(log), "afhub teleop: stopped while waiting for device/absent\n"))
      << read_file(log);
}

// A physics stepping slower than --stale (here every 80 ms: --dt 0.08) goes silent
// between each two steps: teleop said "no state" every 80 ms. It says once that the
// physics is slower than --stale, with what to do, and the device still gets no force;
// killed, the physics is said silent.
TEST(TeleopEndToEnd, APhysicsSlowerThanTheStaleTimeIsSaidOnce) {
  Teleop teleop("slow", {}, {}, {"--dt", "0.08"});
  ASSERT_TRUE(wait_until([&] { return contains(teleop.teleop_log(), "slower than --stale"); }, 20s))
      << teleop.logs();
  bool pushed = false;
  for (int i = 0; i < 1000; ++i) {  // 2 s
    pushed |= teleop.device().gate == ForceGate::kApplying;
    pause_ms(2);
  }
  const std::string log = teleop.teleop_log();
  EXPECT_EQ(occurrences(log, "slower than --stale"), 1) << log;
  EXPECT_TRUE(contains(log, "afhub/gripper/palm publishes a state every 8")) << log;  // 80 ms
  EXPECT_TRUE(contains(log, "slower than --stale (50 ms)")) << log;
  EXPECT_TRUE(contains(log, "Give teleop --stale 1")) << log;  // 120 ms or more
  // The two silences before the second interval was seen.
  EXPECT_LE(occurrences(log, "no state from"), 2) << log;
  EXPECT_FALSE(pushed) << "a force on a physics slower than --stale" << teleop.logs();
  // Dead, it is said so once its silence outlasts three of its gaps.
  teleop.signal_physics(SIGKILL);
  EXPECT_TRUE(wait_until(
      [&] {
        return occurrences(teleop.teleop_log(), "no state from") >
               occurrences(log, "no state from");
      },
      5s))
      << teleop.teleop_log();
}

// --feedback contact: the device renders the palm's contact force (the physics'
// BodyState.contact_wrench), so moving through the air gives no force at all, and
// pushing the palm into the floor an upward force, bounded by the max force.
TEST(TeleopEndToEnd, ContactFeedbackIsZeroInTheAirAndPushesBackOnTheFloor) {
  afhub::testing::ModelFolder scripts;
  // 1 to 2 s: 3 cm along x and 5 cm down in the air (15 cm and 25 cm of palm, still
  // 35 cm above the floor); 3 to 5 s: down 20 cm in all (the proxy 40 cm into the floor).
  const std::string csv =
      scripts.write("contact.csv",
                    "0,0,0,0\n1,0,0,0\n2,0.03,0,-0.05\n3,0.03,0,-0.05\n5,0.03,0,-0.2\n"
                    "9,0.03,0,-0.2\n");
  Teleop teleop("contact", {"--trajectory", csv}, {"--feedback", "contact"});
  ASSERT_TRUE(teleop.restart_driver_once_running()) << teleop.logs();
  double air_most = 0.0, most_force = 0.0, up_force_sum = 0.0, palm_up_sum = 0.0;
  std::uint32_t air_contacts = 0;
  int in_air = 0, pressing = 0;
  for (int i = 0; i < 3500; ++i) {  // about 7 s, every 2 ms
    const DeviceState& device = teleop.device();
    const BodyState& palm = teleop.palm();
    const Vec3& f = device.applied.force_n;
    const double force = std::sqrt(f.x * f.x + f.y * f.y + f.z * f.z);
    most_force = std::max(most_force, force);
    if (device.pose.position_m.z > -0.06) {  // the palm 30 cm or more above the floor
      air_most = std::max(air_most, force);
      air_contacts = std::max(air_contacts, palm.contact_count);
      ++in_air;
    } else if (device.pose.position_m.z < -0.15) {  // the palm on the floor, pushed on
      up_force_sum += f.z;
      palm_up_sum += palm.contact_wrench.force_n.z;
      ++pressing;
    }
    pause_ms(2);
  }
  const double mean_up = pressing ? up_force_sum / pressing : 0.0;
  std::printf(
      "contact feedback: largest force in the air %.3g N (%d samples, at most %u contacts); "
      "pressing: palm contact force up %.2f N, device force up %.3f N (%d samples), largest "
      "%.3f N (max force %.1f N)\n",
      air_most, in_air, air_contacts, pressing ? palm_up_sum / pressing : 0.0, mean_up, pressing,
      most_force, kMaxForce);
  ASSERT_GT(in_air, 500) << teleop.logs();
  ASSERT_GT(pressing, 100) << "the hand never pushed down" << teleop.logs();
  EXPECT_EQ(air_contacts, 0u);
  EXPECT_LT(air_most, 1e-3) << "a force with nothing touched" << teleop.logs();
  EXPECT_GT(palm_up_sum / pressing, 10.0) << "the physics reported no floor contact";
  EXPECT_LE(most_force, kMaxForce + 1e-9) << "the device got more than the max force";
  SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD();
  EXPECT_GT(mean_up, 0.8 * kMaxForce) << "the device got no force opposing the push";
}

// --feedback contact takes the whole multibody's contacts: a wall 2 cm ahead of the
// fingertips (the palm stays 9 cm from it), the hand moving 2 cm toward it (the
// virtual hand yields to the force it gets: it stops about 1.5 cm out, its proxy 5 cm
// into the wall). Only the fingers touch it, and the device is pushed back (-x), away
// from the contact; before it moves, nothing touches and the device
// gets no force. (With the root's contacts only, it got none at all.)
TEST(TeleopEndToEnd, ContactFeedbackFeelsAFingerTouchingAWall) {
  afhub::testing::ModelFolder scripts;
  // A passive box, its face at x 0.71 (the fingertips at 0.69), spanning both fingers.
  const std::string wall = scripts.write("wall.yaml", R"(adf version: '1.0'
bodies: [BODY wall]
joints: []
namespace: /afhub/test_wall/
BODY wall:
  name: wall
  mass: 0.0
  location:
    position: {x: 0.76, y: 0.8, z: 0.6}
    orientation: {r: 0.0, p: 0.0, y: 0.0}
  shape: BOX
  geometry: {x: 0.1, y: 0.3, z: 0.2}
  collision shape: BOX
  collision geometry: {x: 0.1, y: 0.3, z: 0.2}
  passive: true
)");
  const std::string csv =
      scripts.write("finger.csv", "0,0,0,0\n3,0,0,0\n4,0.02,0,0\n10,0.02,0,0\n");
  Teleop teleop("finger", {"--trajectory", csv}, {"--feedback", "contact"}, {wall});
  LatestReader<BodyState> finger(body_state_channel("afhub/gripper/left_finger"));
  ASSERT_TRUE(teleop.restart_driver_once_running()) << teleop.logs();
  double still_most = 0.0, back_sum = 0.0, side_most = 0.0, finger_x_sum = 0.0;
  std::uint32_t palm_contacts = 0, finger_contacts = 0;
  int still = 0, pressing = 0;
  for (int i = 0; i < 3000; ++i) {  // about 6 s, every 2 ms
    const DeviceState& device = teleop.device();
    const Vec3& f = device.applied.force_n;
    palm_contacts = std::max(palm_contacts, teleop.palm().contact_count);
    if (device.pose.position_m.x < 1e-4) {  // the hand not yet moved: nothing touches
      still_most = std::max(still_most, std::sqrt(f.x * f.x + f.y * f.y + f.z * f.z));
      ++still;
    } else if (device.pose.position_m.x > 0.01 && device.gate == ForceGate::kApplying) {
      // The fingers on the wall since the hand's 4 mm: pushing 3 cm of proxy into it.
      back_sum += f.x;
      side_most = std::max(side_most, std::hypot(f.y, f.z));
      if (const BodyState* s = finger.latest()) {
        finger_contacts = std::max(finger_contacts, s->contact_count);
        finger_x_sum += s->contact_wrench.force_n.x;
      }
      ++pressing;
    }
    pause_ms(2);
  }
  const double mean_back = pressing ? back_sum / pressing : 0.0;
  std::printf(
      "finger on a wall: still: largest force %.3g N (%d samples); pressing: device force "
      "along x %.3f N (mean), largest sideways %.3f N, left finger contact force along x "
      "%.2f N (mean), at most %u finger and %u palm contacts (%d samples)\n",
      still_most, still, mean_back, side_most, pressing ? finger_x_sum / pressing : 0.0,
      finger_contacts, palm_contacts, pressing);
  ASSERT_GT(still, 200) << teleop.logs();
  ASSERT_GT(pressing, 200) << "the hand never pushed on with teleop commanding" << teleop.logs();
  EXPECT_LT(still_most, 1e-3) << "a force with nothing touched" << teleop.logs();
  EXPECT_GT(finger_contacts, 0u) << "the finger never touched the wall";
  EXPECT_EQ(palm_contacts, 0u) << "the palm touched something: the test proves nothing";
  EXPECT_LT(mean_back, -0.3) << "the device got no force away from the finger's contact"
                             << teleop.logs();
  EXPECT_LT(side_most, std::abs(mean_back)) << "the force points elsewhere than back";
}

// The teleoperation process SIGKILLed while the device pushes into the floor (more
// than 1 N up on the hand): the driver's watchdog takes the force to zero. The time
// from each kill to the driver's first state at zero force is read from its state
// stamps and printed. Each round starts a new teleop, then a new driver once that
// teleop is bound, so that the hand pushes from the start of its trajectory (a new
// teleop anchors where the hand is: started together with the driver, a teleop slow to
// start under the sanitizers once bound after the trajectory had ended, in round 11 of
// a CI run: no push).
TEST(TeleopEndToEnd, KillingTeleopWhileItPushesZeroesTheForce) {
  afhub::testing::ModelFolder scripts;
  const std::string csv = scripts.write("push.csv", "0,0,0,0\n1,0,0,-0.2\n");
  Teleop teleop("kill", {"--trajectory", csv});
  ASSERT_TRUE(teleop.wait_running()) << teleop.logs();
  constexpr int kKills = 20;
  std::vector<double> kill_to_zero_ms;
  for (int round = 0; round < kKills; ++round) {
    teleop.restart_teleop();
    ASSERT_TRUE(teleop.restart_driver_once_running()) << "round " << round << teleop.logs();
    ASSERT_TRUE(wait_until(
        [&] {
          const DeviceState* d = teleop.new_device_state();
          return d && d->gate == ForceGate::kApplying &&
                 std::hypot(d->applied.force_n.x, d->applied.force_n.y, d->applied.force_n.z) > 1.0;
        },
        20s))
        << "round " << round << ": no force applied" << teleop.logs();
    const std::int64_t killed_at = monotonic_ns();
    teleop.kill_teleop();
    std::int64_t zero_stamp = 0;
    for (const std::int64_t give_up = killed_at + 5'000'000'000LL;
         zero_stamp == 0 && monotonic_ns() < give_up;
         std::this_thread::sleep_for(std::chrono::microseconds(100))) {
      const DeviceState* d = teleop.new_device_state();
      if (d && d->gate == ForceGate::kWatchdog && d->applied.force_n.z == 0.0)
        zero_stamp = d->header.publish_stamp_ns;
    }
    ASSERT_NE(zero_stamp, 0) << "round " << round << ": the force stayed on" << teleop.logs();
    kill_to_zero_ms.push_back(static_cast<double>(zero_stamp - killed_at) * 1e-6);
  }
  std::sort(kill_to_zero_ms.begin(), kill_to_zero_ms.end());
  std::printf(
      "SIGKILL of afhub teleop to zero device force (%d kills): p50 %.2f ms, p99 %.2f ms, max "
      "%.2f ms\n",
      kKills, percentile_of_sorted<double>(kill_to_zero_ms, 0.5),
      percentile_of_sorted<double>(kill_to_zero_ms, 0.99), kill_to_zero_ms.back());
}

// The physics stopped (SIGSTOP), then SIGKILLed, while the device pushes into the floor:
// the palm's states stop, and teleop disables the device's force. Each time, the first
// device state disabled by teleop comes within the staleness bound (teleop's default 50 ms)
// plus one watchdog period of the driver (10 ms), and every later state has zero force
// for as long as the physics is gone. Resumed, the force ramps back in from zero.
constexpr double kStaleMs = 50.0, kWatchdogMs = 10.0;

struct Frozen {
  double to_zero_ms{-1.0};  // from the signal to the first device state at zero force
  int states{0};            // device states read after that one
  int pushing{0};           // of those, with a force
};

// Reads the device's states for `ms` after `signalled_at`.
Frozen watch_force(TeleopSession& teleop, std::int64_t signalled_at, int ms) {
  Frozen frozen;
  for (const std::int64_t until = signalled_at + ms * 1'000'000LL; monotonic_ns() < until;
       std::this_thread::sleep_for(std::chrono::microseconds(200))) {
    const DeviceState* d = teleop.new_device_state();
    if (!d) continue;
    const bool zero =
        d->applied.force_n.x == 0.0 && d->applied.force_n.y == 0.0 && d->applied.force_n.z == 0.0;
    if (frozen.to_zero_ms < 0.0) {
      // Teleop's own gate: its command disables the force. (A zero from the driver's
      // watchdog while teleop itself is late, as once under the sanitizers beside other
      // tests, comes and goes within the staleness bound: not the gate.)
      if (zero && d->gate == ForceGate::kDisabled)
        frozen.to_zero_ms = static_cast<double>(d->header.publish_stamp_ns - signalled_at) * 1e-6;
      continue;
    }
    ++frozen.states;
    if (!zero) ++frozen.pushing;
  }
  return frozen;
}

// The first force the driver logged after it logged none, in its --force-log from byte
// `from` on, or -1 if none came within `timeout`. The driver logs every change between
// force and none, where reading device states missed the ramp's first tens of
// milliseconds under the sanitizers.
double first_logged_force_after_off(const std::string& force_log, std::size_t from,
                                    std::chrono::milliseconds timeout) {
  double force = -1.0;
  wait_until(
      [&] {
        std::istringstream lines(read_file(force_log).substr(from));
        bool off = false;
        for (std::string line; std::getline(lines, line);) {
          off = off || line.find(" zero") != std::string::npos;
          double x = 0, y = 0, z = 0;
          if (off && std::sscanf(line.c_str(), "%*s force %lf %lf %lf", &x, &y, &z) == 3) {
            force = std::hypot(x, y, z);
            return true;
          }
        }
        return false;
      },
      timeout);
  return force;
}

bool pushing_up(TeleopSession& teleop) {
  const DeviceState* d = teleop.new_device_state();
  return d && d->gate == ForceGate::kApplying && d->applied.force_n.z > 1.0;
}

// A state said once in `window` (teleop's log over some seconds), or once more after
// each silence said there: a physics stalled under load is said silent, then the state
// again.
void expect_said_once_but_for_silences(const std::string& window, const std::string& said) {
  const int times = occurrences(window, said);
  EXPECT_GE(times, 1) << window;
  EXPECT_LE(times, 1 + occurrences(window, "no state from")) << window;
}

TEST(TeleopEndToEnd, ADeviceNeverPushesOnAStoppedOrDeadPhysics) {
  afhub::testing::ModelFolder scripts;
  const std::string csv = scripts.write("push.csv", "0,0,0,0\n1,0,0,-0.2\n");
  const std::string force_log = (scripts.dir() / "force.log").string();
  Teleop teleop("frozen", {"--trajectory", csv, "--force-log", force_log});
  ASSERT_TRUE(teleop.restart_driver_once_running()) << teleop.logs();
  ASSERT_TRUE(wait_until([&] { return pushing_up(teleop); }, 20s)) << teleop.logs();

  // Each loss said once (counted from before it: a physics stalled longer than the
  // staleness limit before, under load, was said too).
  const std::string said = "no state from afhub/gripper/palm";
  const int said_before_stop = occurrences(teleop.teleop_log(), said);
  const std::size_t log_before_stop = read_file(force_log).size();
  const std::int64_t stopped_at = monotonic_ns();
  teleop.signal_physics(SIGSTOP);
  const Frozen stopped = watch_force(teleop, stopped_at, 3000);
  teleop.signal_physics(SIGCONT);
  EXPECT_EQ(occurrences(teleop.teleop_log(), said), said_before_stop + 1) << teleop.teleop_log();

  // Back: teleop says so, and the driver ramps the force in from zero (0.2 s to full).
  ASSERT_TRUE(wait_until(
      [&] { return contains(teleop.teleop_log(), "afhub/gripper/palm's physics steps again"); },
      5s))
      << teleop.logs();
  const double first_force = first_logged_force_after_off(force_log, log_before_stop, 5s);
  ASSERT_GE(first_force, 0.0) << read_file(force_log) << teleop.logs();
  ASSERT_TRUE(wait_until([&] { return pushing_up(teleop); }, 20s)) << teleop.logs();

  // A paused world publishes its states on, unmoving, while the device moves on: the
  // force it would render grew to the file's maximum. No force while paused.
  const std::size_t log_before_pause = teleop.teleop_log().size();
  const std::int64_t paused_at = monotonic_ns();
  ASSERT_EQ(run_afhub({"world", "pause"}).exit_code, 0);
  const Frozen paused = watch_force(teleop, paused_at, 3000);
  ASSERT_EQ(run_afhub({"world", "resume"}).exit_code, 0);
  expect_said_once_but_for_silences(teleop.teleop_log().substr(log_before_pause),
                                    "afhub/gripper/palm's world is paused");
  ASSERT_TRUE(wait_until([&] { return pushing_up(teleop); }, 20s)) << teleop.logs();

  const int said_before_kill = occurrences(teleop.teleop_log(), said);
  const std::int64_t killed_at = monotonic_ns();
  teleop.signal_physics(SIGKILL);
  const Frozen killed = watch_force(teleop, killed_at, 3000);
  EXPECT_EQ(occurrences(teleop.teleop_log(), said), said_before_kill + 1) << teleop.teleop_log();

  std::printf(
      "physics stopped: force zero %.1f ms after SIGSTOP, then %d of %d device states with a "
      "force; resumed: first force %.3f N; world paused: zero %.1f ms after the pause, then %d "
      "of %d with a force; physics killed: zero %.1f ms after SIGKILL, then %d of %d with a "
      "force\n",
      stopped.to_zero_ms, stopped.pushing, stopped.states, first_force, paused.to_zero_ms,
      paused.pushing, paused.states, killed.to_zero_ms, killed.pushing, killed.states);
  for (const Frozen& frozen : {stopped, paused, killed}) {
    ASSERT_GE(frozen.to_zero_ms, 0.0) << "the device kept pushing" << teleop.logs();
    EXPECT_GT(frozen.states, 300) << "the driver stopped publishing" << teleop.logs();
    EXPECT_EQ(frozen.pushing, 0) << "the device pushed again on a gone physics" << teleop.logs();
  }
  EXPECT_LT(first_force, 0.5) << "the force came back at once, not ramped in";
  SKIP_REAL_TIME_BOUNDS_IN_SANITIZED_BUILD();
  EXPECT_LE(stopped.to_zero_ms, kStaleMs + kWatchdogMs) << teleop.logs();
  EXPECT_LE(killed.to_zero_ms, kStaleMs + kWatchdogMs) << teleop.logs();
}

// A paused world stepped by hand (`afhub world step 1`) while the device pushes into the
// floor: each step moved the palm, looked live until it had stayed for the stale time, and
// the force ramped in for those 50 ms (0.026 N seen). Teleop reads the world's paused flag:
// no force until the world runs again.
TEST(TeleopEndToEnd, APausedWorldSteppedByHandGivesNoForce) {
  afhub::testing::ModelFolder scripts;
  const std::string csv = scripts.write("push.csv", "0,0,0,0\n1,0,0,-0.2\n");
  const std::string force_log = (scripts.dir() / "force.log").string();
  Teleop teleop("stepped", {"--trajectory", csv, "--force-log", force_log});
  ASSERT_TRUE(teleop.restart_driver_once_running()) << teleop.logs();
  ASSERT_TRUE(wait_until([&] { return pushing_up(teleop); }, 20s)) << teleop.logs();

  const std::string paused_said = "afhub/gripper/palm's world is paused";
  const std::size_t log_before = teleop.teleop_log().size();
  const std::size_t log_before_pause = read_file(force_log).size();
  const int zeros_before = occurrences(read_file(force_log), " zero");
  ASSERT_EQ(run_afhub({"world", "pause"}).exit_code, 0);
  ASSERT_TRUE(
      wait_until([&] { return contains(teleop.teleop_log().substr(log_before), paused_said); }, 5s))
      << teleop.logs();
  ASSERT_TRUE(
      wait_until([&] { return occurrences(read_file(force_log), " zero") > zeros_before; }, 5s))
      << read_file(force_log) << teleop.logs();
  const std::size_t before = read_file(force_log).size();
  const std::uint64_t step_before = teleop.palm().header.sim_step;
  // Single steps, each past the stale time (a step by hand looked live for that long),
  // and runs of 5 and 50 steps (the world state says halted only once they are done).
  const std::vector<int> steps = {1, 1, 1, 5, 50};
  int asked = 0;
  for (const int n : steps) {
    ASSERT_EQ(run_afhub({"world", "step", std::to_string(n)}).exit_code, 0) << asked;
    asked += n;
    pause_ms(150);
  }
  const std::string after = read_file(force_log).substr(before);
  const std::string said = teleop.teleop_log().substr(log_before);
  const std::uint64_t stepped = teleop.palm().header.sim_step - step_before;
  std::printf("paused world stepped by hand %llu steps: force log after the pause: \"%s\"\n",
              static_cast<unsigned long long>(stepped), after.c_str());
  EXPECT_EQ(stepped, static_cast<std::uint64_t>(asked)) << "the world did not step by hand";
  EXPECT_FALSE(contains(after, " force ")) << "the device pushed on a paused world\n"
                                           << after << teleop.logs();
  expect_said_once_but_for_silences(said, paused_said);
  EXPECT_FALSE(contains(said, "steps again")) << said;

  // Running again: said, and the force ramps in.
  const std::size_t log_before_resume = teleop.teleop_log().size();
  ASSERT_EQ(run_afhub({"world", "resume"}).exit_code, 0);
  ASSERT_TRUE(wait_until(
      [&] {
        return contains(teleop.teleop_log().substr(log_before_resume),
                        "afhub/gripper/palm's physics steps again");
      },
      5s))
      << teleop.logs();
  const double first_force = first_logged_force_after_off(force_log, log_before_pause, 5s);
  ASSERT_GE(first_force, 0.0) << read_file(force_log) << teleop.logs();
  EXPECT_LT(first_force, 0.5) << "the force came back at once, not ramped in";
}

// A world reset while the device pushes into the floor: the palm is back at its start,
// 0.2 m from where the device holds it, and its states never stopped. The force went on
// at once with the whole new error behind it; now teleop takes it off until the world
// steps again (at least kRestartOffNs), and the driver ramps it in from zero. The same
// holds for a physics restarted within the stale time (its sequence from 1 again).
TEST(TeleopEndToEnd, AWorldResetWhileTheDevicePushesRampsTheForceInAgain) {
  afhub::testing::ModelFolder scripts;
  const std::string csv = scripts.write("push.csv", "0,0,0,0\n1,0,0,-0.2\n");
  // The driver logs each change between force and none: it sees every cycle, where this
  // test's reads missed the 20 ms without force under the sanitizers.
  const std::string force_log = (scripts.dir() / "force.log").string();
  Teleop teleop("reset", {"--trajectory", csv, "--force-log", force_log});
  ASSERT_TRUE(teleop.restart_driver_once_running()) << teleop.logs();
  ASSERT_TRUE(wait_until([&] { return pushing_up(teleop); }, 20s)) << teleop.logs();

  const std::size_t before = read_file(force_log).size();
  ASSERT_EQ(run_afhub({"world", "reset"}).exit_code, 0);
  // Said, the force off, then on again from the ramp's start.
  ASSERT_TRUE(wait_until(
      [&] { return contains(teleop.teleop_log(), "afhub/gripper/palm's physics steps again"); },
      10s))
      << teleop.logs();
  const double first_force = first_logged_force_after_off(force_log, before, 10s);
  ASSERT_GE(first_force, 0.0) << "the force never went off and came back\n"
                              << read_file(force_log) << teleop.logs();
  std::printf("world reset while pushing: first force after it %.3f N\n", first_force);
  EXPECT_LT(first_force, 0.5) << "the force came back at once, not ramped in";
  EXPECT_EQ(occurrences(teleop.teleop_log(), "afhub/gripper/palm's states went back to step"), 1)
      << teleop.teleop_log();
}

// The same standstill with a driver whose watchdog outlasts it (300 ms against teleop's
// 50 ms stale time) while the device pushes: the driver kept the force on meanwhile, so
// teleop goes on as after a late cycle. Taken for a standstill, the 3 N dropped to none
// and ramped in again.
TEST(TeleopEndToEnd, AStandstillTheDriverOutlastedKeepsTheForce) {
  afhub::testing::ModelFolder scripts;
  const std::string csv = scripts.write("push.csv", "0,0,0,0\n1,0,0,-0.2\n");
  const std::string force_log = (scripts.dir() / "force.log").string();
  Teleop teleop("outlasted", {"--trajectory", csv, "--watchdog", "300", "--force-log", force_log});
  ASSERT_TRUE(teleop.restart_driver_once_running()) << teleop.logs();
  ASSERT_TRUE(wait_until([&] { return pushing_up(teleop); }, 20s)) << teleop.logs();
  pause_ms(300);
  const std::size_t before = read_file(force_log).size();
  teleop.signal_teleop(SIGSTOP);
  pause_ms(100);
  teleop.signal_teleop(SIGCONT);
  pause_ms(500);
  const std::string after = read_file(force_log).substr(before);
  EXPECT_FALSE(contains(after, " zero")) << "the force went off\n" << after << teleop.logs();
  EXPECT_FALSE(contains(teleop.teleop_log(), "stood still")) << teleop.teleop_log();
  EXPECT_TRUE(wait_until([&] { return pushing_up(teleop); }, 2s)) << teleop.logs();
}

}  // namespace
}  // namespace afhub::test
