// The rules every device driver enforces (ForceSafety) and the virtual device, without
// a hub: the watchdog, the clamp that keeps the direction, the ramp, and a hand that
// follows its trajectory and gives way to the applied force. A cycle of either
// allocates nothing.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <new>

#include "afhub/devices/force_safety.hpp"
#include "afhub/devices/virtual_device.hpp"
#include "afhub/shm_layout/error.hpp"
#include "heap_counter.hpp"

namespace afhub::devices {
namespace {

constexpr std::int64_t kMs = 1'000'000;

double length(const Vec3& v) {
  return std::hypot(v.x, v.y, v.z);
}

DeviceCommand command_at(std::int64_t stamp_ns, Vec3 force, bool enable = true) {
  DeviceCommand command;
  command.header.publish_stamp_ns = stamp_ns;
  command.wrench.force_n = force;
  command.enable = enable ? 1 : 0;
  return command;
}

class Safety : public ::testing::Test {
 protected:
  DeviceSpec spec_ = [] {
    DeviceSpec spec = VirtualDevice::default_spec(8.0);
    spec.max_torque_nm = 0.5;
    spec.max_gripper_force_n = 2.0;
    return spec;
  }();
  SafetyLimits limits_{10 * kMs, 0.1};
  ForceSafety safety_{spec_, limits_};
  ForceGate gate_ = ForceGate::kApplying;

  // A 1 kHz driver's cycles from `from` to `to` (both included), each with a fresh
  // `command`; the last one's output.
  DeviceOutput cycles(DeviceCommand command, std::int64_t from, std::int64_t to) {
    DeviceOutput out;
    for (std::int64_t now = from; now <= to; now += kMs) {
      command.header.publish_stamp_ns = now;
      out = safety_.apply(&command, now, gate_);
    }
    return out;
  }
};

TEST_F(Safety, NoCommandGivesNoForce) {
  const DeviceOutput out = safety_.apply(nullptr, 5 * kMs, gate_);
  EXPECT_EQ(gate_, ForceGate::kNoCommand);
  EXPECT_EQ(length(out.wrench.force_n), 0.0);
}

TEST_F(Safety, ForceRampsInOverTheRampTime) {
  const std::int64_t now = 1000 * kMs;
  const DeviceCommand command = command_at(now, {2.0, 0.0, 0.0});
  EXPECT_NEAR(safety_.apply(&command, now, gate_).wrench.force_n.x, 0.0, 1e-12);
  EXPECT_EQ(gate_, ForceGate::kApplying);
  // Half the ramp (50 ms) later, with fresh commands: half the force.
  EXPECT_NEAR(cycles(command, now + kMs, now + 50 * kMs).wrench.force_n.x, 1.0, 1e-9);
  EXPECT_NEAR(cycles(command, now + 51 * kMs, now + 110 * kMs).wrench.force_n.x, 2.0, 1e-12);
}

// The driver stopped (SIGSTOP) while its client went on writing: on resuming, the command
// is fresh, and the force it had ramped to came back in one cycle.
TEST_F(Safety, ADriverStoppedForLongerThanTheWatchdogRampsInAgain) {
  const DeviceCommand command = command_at(0, {2.0, 0.0, 0.0});
  ASSERT_NEAR(cycles(command, 0, 200 * kMs).wrench.force_n.x, 2.0, 1e-12);
  // Stopped for 2 s: fresh commands all along, none read.
  const std::int64_t resumed = 2200 * kMs;
  EXPECT_NEAR(cycles(command, resumed, resumed).wrench.force_n.x, 0.0, 1e-12);
  EXPECT_EQ(gate_, ForceGate::kApplying);
  EXPECT_NEAR(cycles(command, resumed + kMs, resumed + 50 * kMs).wrench.force_n.x, 1.0, 1e-9);
  // A late cycle within the watchdog is no interruption.
  const std::int64_t late = resumed + 50 * kMs + limits_.watchdog_ns;
  EXPECT_NEAR(cycles(command, late, late).wrench.force_n.x, 2.0 * 60 / 100, 1e-9);
}

TEST_F(Safety, ClampKeepsTheDirection) {
  const std::int64_t now = 1000 * kMs;
  const DeviceCommand command = command_at(now - 200 * kMs, {100.0, -200.0, 200.0});
  const DeviceOutput out = cycles(command, now - 200 * kMs, now);  // past the ramp
  EXPECT_NEAR(length(out.wrench.force_n), spec_.max_force_n, 1e-9);
  EXPECT_NEAR(out.wrench.force_n.x / out.wrench.force_n.z, 0.5, 1e-12);
  EXPECT_NEAR(out.wrench.force_n.y / out.wrench.force_n.z, -1.0, 1e-12);
}

TEST_F(Safety, TorqueAndGripperAreClampedToo) {
  DeviceCommand command = command_at(0, {});
  command.wrench.torque_nm = {0.0, 3.0, 4.0};
  command.gripper_force_n = -50.0;
  const DeviceOutput out = cycles(command, 0, 200 * kMs);  // past the ramp
  EXPECT_NEAR(length(out.wrench.torque_nm), 0.5, 1e-12);
  EXPECT_NEAR(out.gripper_force_n, -2.0, 1e-12);
}

TEST_F(Safety, AStaleCommandGivesZeroAndTheRampStartsOver) {
  std::int64_t now = 1000 * kMs;
  DeviceCommand command = command_at(now, {1.0, 0.0, 0.0});
  for (int i = 0; i < 200; ++i, now += kMs) {
    command.header.publish_stamp_ns = now;
    safety_.apply(&command, now, gate_);
  }
  ASSERT_NEAR(safety_.apply(&command, now, gate_).wrench.force_n.x, 1.0, 1e-9);
  // The writer stops: 10 ms later it still applies, 1 ns beyond it is zero.
  const std::int64_t last = command.header.publish_stamp_ns;
  EXPECT_GT(safety_.apply(&command, last + limits_.watchdog_ns, gate_).wrench.force_n.x, 0.0);
  EXPECT_EQ(safety_.apply(&command, last + limits_.watchdog_ns + 1, gate_).wrench.force_n.x, 0.0);
  EXPECT_EQ(gate_, ForceGate::kWatchdog);
  // The writer comes back: the force ramps in again from zero.
  now = last + 500 * kMs;
  command.header.publish_stamp_ns = now;
  EXPECT_NEAR(safety_.apply(&command, now, gate_).wrench.force_n.x, 0.0, 1e-12);
}

TEST_F(Safety, TheForceIsZeroWithinTheWatchdogNotACycleLater) {
  ForceSafety safety(spec_, {10 * kMs, 0.0, kMs});  // a 1 kHz driver
  const DeviceCommand command = command_at(0, {1.0, 0.0, 0.0});
  EXPECT_EQ(safety.apply(&command, 9 * kMs, gate_).wrench.force_n.x, 1.0);
  // At 9.5 ms the next cycle would come past 10 ms: zero now.
  EXPECT_EQ(safety.apply(&command, 9 * kMs + kMs / 2, gate_).wrench.force_n.x, 0.0);
  EXPECT_EQ(gate_, ForceGate::kWatchdog);
}

TEST_F(Safety, AStampFromTheFutureIsNotFresh) {
  const DeviceCommand command = command_at(1000 * kMs, {1.0, 0.0, 0.0});
  EXPECT_EQ(safety_.apply(&command, 500 * kMs, gate_).wrench.force_n.x, 0.0);
  EXPECT_EQ(gate_, ForceGate::kWatchdog);
}

TEST_F(Safety, DisabledAndStoppingGiveZero) {
  const DeviceCommand off = command_at(0, {1.0, 0.0, 0.0}, false);
  EXPECT_EQ(safety_.apply(&off, 0, gate_).wrench.force_n.x, 0.0);
  EXPECT_EQ(gate_, ForceGate::kDisabled);
  const DeviceCommand on = command_at(0, {1.0, 0.0, 0.0});
  safety_.stop();
  EXPECT_EQ(safety_.apply(&on, 0, gate_).wrench.force_n.x, 0.0);
  EXPECT_EQ(gate_, ForceGate::kStopping);
}

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

TEST(VirtualHandTest, FollowsItsTrajectory) {
  // 2 cm along x over 2 s, then held: the hand settles on it.
  VirtualDevice device({{0.0, {0, 0, 0}, 0, 0}, {2.0, {0.02, 0, 0}, 0, 0}}, false,
                       VirtualDevice::default_spec());
  DeviceSample sample;
  double worst_lag = 0.0;
  for (int ms = 0; ms <= 4000; ++ms) {
    sample = device.step({}, ms * 1e-3);
    if (ms > 500 && ms < 2000)
      worst_lag = std::max(worst_lag, std::abs(sample.pose.position_m.x - 0.01 * ms * 1e-3));
  }
  EXPECT_LT(worst_lag, 5e-4) << "the hand lags its trajectory by more than 0.5 mm";
  EXPECT_NEAR(sample.pose.position_m.x, 0.02, 1e-5);
  EXPECT_NEAR(sample.velocity.linear_mps.x, 0.0, 1e-4);
}

TEST(VirtualHandTest, GivesWayToTheAppliedForce) {
  VirtualHand hand;
  VirtualDevice device({TrajectoryPoint{}}, false, VirtualDevice::default_spec(), hand);
  DeviceOutput push;
  push.wrench.force_n = {0.0, 0.0, -2.0};
  DeviceSample sample;
  for (int ms = 0; ms <= 3000; ++ms) sample = device.step(push, ms * 1e-3);
  // At rest the arm's spring balances the force: z = F / k.
  EXPECT_NEAR(sample.pose.position_m.z, -2.0 / hand.stiffness_npm, 1e-5);
}

TEST(VirtualHandTest, ButtonsAndGripperComeFromTheScript) {
  const std::string path = write_file("buttons.csv",
                                      "t,x,y,z,buttons,gripper\n"
                                      "0, 0, 0, 0, 0, 0.1\n"
                                      "1, 0, 0, 0, 5, 0.4  # clutch and another\n");
  VirtualDevice device(read_trajectory_csv(path), false, VirtualDevice::default_spec());
  EXPECT_EQ(device.step({}, 0.5).buttons, 0u);
  const DeviceSample later = device.step({}, 1.2);
  EXPECT_EQ(later.buttons, 5u);
  EXPECT_DOUBLE_EQ(later.gripper_angle_rad, 0.4);
}

TEST(VirtualHandTest, ALoopedTrajectoryStartsOver) {
  VirtualDevice device({{0.0, {0, 0, 0}, 1, 0}, {1.0, {0, 0, 0}, 2, 0}}, true,
                       VirtualDevice::default_spec());
  EXPECT_EQ(device.step({}, 0.5).buttons, 1u);
  EXPECT_EQ(device.step({}, 1.5).buttons, 1u);
}

TEST(TrajectoryCsvTest, BadLinesAreLocated) {
  const auto error_of = [](const std::string& text) -> std::string {
    try {
      read_trajectory_csv(write_file("bad.csv", text));
    } catch (const Error& error) {
      return error.what();
    }
    return "no error";
  };
  EXPECT_NE(error_of("0,0,0,0\n0,1,1,1\n").find("bad.csv:2: time 0"), std::string::npos)
      << error_of("0,0,0,0\n0,1,1,1\n");
  EXPECT_NE(error_of("0,0,0\n").find("bad.csv:1: expected 4 to 6 values"), std::string::npos);
  EXPECT_NE(error_of("0,0,0,0\n1,0,x,0\n").find("bad.csv:2: expected numbers"), std::string::npos);
  // strtod read it as 16.
  EXPECT_NE(error_of("0,0,0,0\n1,0,0x10,0\n").find("bad.csv:2: expected numbers"),
            std::string::npos);
  EXPECT_NE(error_of("0,0,0,0,-1\n").find("buttons must be a bit mask"), std::string::npos);
  EXPECT_NE(error_of("# nothing\n").find("has no points"), std::string::npos);
  EXPECT_NE(error_of("0,0,0,0,1.5\n").find("buttons must be a bit mask"), std::string::npos);
  // Points near the largest doubles interpolated to a pose that was not finite.
  EXPECT_NE(
      error_of("0,1e308,0,0\n1,-1e308,0,0\n").find("bad.csv:1: position 1e+308 m is beyond 10 m"),
      std::string::npos)
      << error_of("0,1e308,0,0\n");
  EXPECT_NE(error_of("-1,0,0,0\n").find("bad.csv:1: time -1"), std::string::npos);
  // Times that differ past the sixth digit read apart.
  EXPECT_NE(error_of("1.0000002,0,0,0\n1.0000001,0,0,0\n")
                .find("bad.csv:2: time 1.0000001 s does not come after the line before's "
                      "1.0000002 s"),
            std::string::npos)
      << error_of("1.0000002,0,0,0\n1.0000001,0,0,0\n");
  EXPECT_NE(error_of("0,0,0,0,0,1e300\n").find("the gripper angle"), std::string::npos);
  // A file that never ends was read until memory ran out.
  std::string never_ends;
  try {
    read_trajectory_csv("/dev/zero");
  } catch (const Error& error) {
    never_ends = error.what();
  }
  EXPECT_NE(never_ends.find("not a regular file"), std::string::npos) << never_ends;
}

TEST(DeviceCycleTest, AllocatesNothing) {
  VirtualDevice device(circle_trajectory(0.02, 1.0), true, VirtualDevice::default_spec());
  ForceSafety safety(device.spec(), {});
  DeviceCommand command = command_at(0, {1.0, 2.0, 3.0});
  ForceGate gate{};
  device.step({}, 0.0);
  const long before = test::heap_allocations();
  for (int ms = 1; ms < 5000; ++ms) {
    command.header.publish_stamp_ns = ms * kMs;
    device.step(safety.apply(&command, ms * kMs, gate), ms * 1e-3);
  }
  EXPECT_EQ(test::heap_allocations() - before, 0);
}

}  // namespace
}  // namespace afhub::devices
