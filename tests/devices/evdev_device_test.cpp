// EvdevDevice, the real libevdev code over umockdev-emulated evdev nodes (this kernel
// has no uinput): events in, DeviceSample out; the mapping of SpaceMice (EV_ABS and
// EV_REL) and gamepads; the pose kept within the workspace; unplugging.
#include "afhub/devices/evdev_device.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <string>

#include "emulated_devices.hpp"
#include "heap_counter.hpp"

namespace afhub::devices {
namespace {

using test::Testbed;

// The device's clock is driven by the test, never the machine's.
std::int64_t fake_now_ns = 0;
std::int64_t fake_clock() {
  return fake_now_ns;
}

EvdevOptions velocity_options() {
  EvdevOptions options;
  options.mode = EvdevAxisMode::kVelocity;
  options.linear_speed_mps = 0.1;
  options.angular_speed_radps = 2.0;
  options.deadband = 0.05;
  options.clock_ns = fake_clock;
  return options;
}

// A deflection of `fraction` of full scale after the 0.05 deadband.
double banded(double fraction) {
  return (fraction - 0.05) / 0.95;
}

TEST(EvdevDevice, SpaceMouseSpecComesFromTheDevice) {
  Testbed testbed;
  auto& mouse = testbed.add_input(5, test::spacemouse_compact());
  EvdevDevice device(mouse.path(), velocity_options());
  const DeviceSpec spec = device.spec();
  EXPECT_EQ(std::string(spec.model.data()), "3Dconnexion SpaceMouse Compact");
  EXPECT_EQ(std::string(spec.serial.data()), "SMC-1234");
  EXPECT_EQ(spec.max_force_n, 0.0);
  EXPECT_EQ(spec.actuated, 0U);
  EXPECT_EQ(spec.sensed, kDeviceTranslation | kDeviceRotation);
  EXPECT_EQ(spec.button_count, 2U);
  EXPECT_EQ(device.layout(), EvdevLayout::kSixAxis);
}

TEST(EvdevDevice, SpaceMouseAbsoluteAxesAndButtons) {
  Testbed testbed;
  auto& mouse = testbed.add_input(5, test::spacemouse_compact());
  EvdevDevice device(mouse.path(), velocity_options());
  DeviceSample rest = device.exchange({});
  EXPECT_EQ(rest.velocity.linear_mps.x, 0.0);
  EXPECT_EQ(rest.buttons, 0U);

  mouse.send(EV_ABS, ABS_X, 350);
  mouse.send(EV_ABS, ABS_Y, -175);
  mouse.send(EV_ABS, ABS_Z, 13);  // within the deadband (and a CR byte through the pty)
  mouse.send(EV_ABS, ABS_RY, 350);
  mouse.send(EV_ABS, ABS_RZ, -262);
  mouse.send(EV_KEY, BTN_1, 1);
  mouse.sync();
  DeviceSample sample = device.exchange({});
  EXPECT_NEAR(sample.velocity.linear_mps.x, 0.1, 1e-12);
  EXPECT_NEAR(sample.velocity.linear_mps.y, -0.1 * banded(0.5), 1e-12);
  EXPECT_EQ(sample.velocity.linear_mps.z, 0.0);
  EXPECT_EQ(sample.velocity.angular_radps.x, 0.0);
  EXPECT_NEAR(sample.velocity.angular_radps.y, 2.0, 1e-12);
  EXPECT_NEAR(sample.velocity.angular_radps.z, -2.0 * banded(262.0 / 350.0), 1e-12);
  EXPECT_EQ(sample.buttons, 0b10U);
  EXPECT_EQ(device.button_code(1), BTN_1);
  // Velocity mode: the pose stays at the origin.
  EXPECT_EQ(sample.pose.position_m.x, 0.0);

  mouse.send(EV_KEY, BTN_1, 0);
  mouse.send(EV_KEY, BTN_0, 1);
  mouse.send(EV_ABS, ABS_X, 0);
  mouse.sync();
  sample = device.exchange({});
  EXPECT_EQ(sample.buttons, 0b01U);
  EXPECT_EQ(sample.velocity.linear_mps.x, 0.0);
  // Nothing new: the state holds.
  sample = device.exchange({});
  EXPECT_EQ(sample.buttons, 0b01U);
  EXPECT_NEAR(sample.velocity.angular_radps.y, 2.0, 1e-12);
}

TEST(EvdevDevice, PoseModeIntegratesWithinTheWorkspace) {
  Testbed testbed;
  auto& mouse = testbed.add_input(5, test::spacemouse_compact());
  EvdevOptions options = velocity_options();
  options.mode = EvdevAxisMode::kPose;
  options.workspace_radius_m = 0.05;
  EvdevDevice device(mouse.path(), options);
  EXPECT_EQ(device.spec().workspace_radius_m, 0.05);

  mouse.send(EV_ABS, ABS_X, 350);   // 0.1 m/s along x
  mouse.send(EV_ABS, ABS_RZ, 350);  // 2 rad/s about z
  mouse.sync();
  fake_now_ns = 1'000'000'000;
  DeviceSample sample = device.exchange({});  // the first exchange starts the clock
  EXPECT_EQ(sample.pose.position_m.x, 0.0);
  for (int i = 0; i < 10; ++i) {
    fake_now_ns += 10'000'000;  // 10 ms
    sample = device.exchange({});
  }
  EXPECT_NEAR(sample.pose.position_m.x, 0.01, 1e-9);
  EXPECT_NEAR(sample.pose.position_m.y, 0.0, 1e-12);
  // 0.2 rad about z.
  EXPECT_NEAR(sample.pose.orientation.z, std::sin(0.1), 1e-9);
  EXPECT_NEAR(sample.pose.orientation.w, std::cos(0.1), 1e-9);

  for (int i = 0; i < 100; ++i) {
    fake_now_ns += 10'000'000;
    sample = device.exchange({});
  }
  EXPECT_NEAR(sample.pose.position_m.x, 0.05, 1e-12);  // held at the workspace's edge
}

TEST(EvdevDevice, RelativeSpaceMouseFramesAndRelease) {
  Testbed testbed;
  auto& mouse = testbed.add_input(6, test::space_navigator_relative());
  EvdevOptions options = velocity_options();
  options.rel_hold_s = 0.1;
  EvdevDevice device(mouse.path(), options);
  EXPECT_EQ(device.layout(), EvdevLayout::kSixAxis);
  EXPECT_EQ(device.spec().serial[0], '\0');

  fake_now_ns = 5'000'000'000;
  mouse.send(EV_REL, REL_X, 175);
  mouse.send(EV_REL, REL_Z, -350);
  mouse.sync();
  mouse.send(EV_REL, REL_RX, 350);
  mouse.sync();
  DeviceSample sample = device.exchange({});
  EXPECT_NEAR(sample.velocity.linear_mps.x, 0.1 * banded(0.5), 1e-12);
  EXPECT_NEAR(sample.velocity.linear_mps.z, -0.1, 1e-12);
  EXPECT_NEAR(sample.velocity.angular_radps.x, 2.0, 1e-12);

  // A translation frame without x: x was zero (the kernel drops zero counts);
  // the rotation, from another report, holds.
  fake_now_ns += 50'000'000;
  mouse.send(EV_REL, REL_Y, 350);
  mouse.sync();
  sample = device.exchange({});
  EXPECT_EQ(sample.velocity.linear_mps.x, 0.0);
  EXPECT_NEAR(sample.velocity.linear_mps.y, 0.1, 1e-12);
  EXPECT_EQ(sample.velocity.linear_mps.z, 0.0);
  EXPECT_NEAR(sample.velocity.angular_radps.x, 2.0, 1e-12);

  // No report for longer than the hold: the cap was released.
  fake_now_ns += 120'000'000;
  sample = device.exchange({});
  EXPECT_EQ(sample.velocity.linear_mps.y, 0.0);
  EXPECT_EQ(sample.velocity.angular_radps.x, 0.0);
}

TEST(EvdevDevice, GamepadSticksTriggersAndButtons) {
  Testbed testbed;
  auto& pad = testbed.add_input(7, test::gamepad());
  EvdevDevice device(pad.path(), velocity_options());
  EXPECT_EQ(device.layout(), EvdevLayout::kGamepad);
  EXPECT_EQ(device.spec().button_count, 8U);

  pad.send(EV_ABS, ABS_X, 32767);
  pad.send(EV_ABS, ABS_Y, -32768);  // left stick pushed up
  pad.send(EV_ABS, ABS_RZ, 255);    // right trigger fully in
  pad.send(EV_ABS, ABS_RX, 32767);  // right stick right
  pad.send(EV_ABS, ABS_HAT0X, -1);  // d-pad left
  pad.send(EV_KEY, BTN_SOUTH, 1);
  pad.send(EV_KEY, BTN_START, 1);
  pad.sync();
  DeviceSample sample = device.exchange({});
  EXPECT_NEAR(sample.velocity.linear_mps.x, 0.1, 1e-4);
  EXPECT_NEAR(sample.velocity.linear_mps.y, 0.1, 1e-4);
  EXPECT_NEAR(sample.velocity.linear_mps.z, 0.1, 1e-4);
  EXPECT_NEAR(sample.velocity.angular_radps.x, -2.0, 1e-4);
  EXPECT_NEAR(sample.velocity.angular_radps.z, -2.0, 1e-4);
  EXPECT_EQ(sample.velocity.angular_radps.y, 0.0);
  EXPECT_EQ(sample.buttons, (1U << 0) | (1U << 7));
  EXPECT_EQ(device.button_code(7), BTN_START);

  // A stick resting slightly off centre and a released trigger read as rest.
  pad.send(EV_ABS, ABS_X, 300);
  pad.send(EV_ABS, ABS_Y, -300);
  pad.send(EV_ABS, ABS_RZ, 0);
  pad.send(EV_KEY, BTN_SOUTH, 0);
  pad.sync();
  sample = device.exchange({});
  EXPECT_EQ(sample.velocity.linear_mps.x, 0.0);
  EXPECT_EQ(sample.velocity.linear_mps.y, 0.0);
  EXPECT_EQ(sample.velocity.linear_mps.z, 0.0);
  EXPECT_EQ(sample.buttons, 1U << 7);
}

TEST(EvdevDevice, ExchangeDoesNotAllocate) {
  Testbed testbed;
  auto& pad = testbed.add_input(7, test::gamepad());
  EvdevOptions options = velocity_options();
  options.mode = EvdevAxisMode::kPose;
  EvdevDevice device(pad.path(), options);
  double sum = 0.0;
  long allocations = 0;
  for (int i = 0; i < 50; ++i) {
    pad.send(EV_ABS, ABS_X, 1000 * i);
    pad.send(EV_KEY, BTN_SOUTH, i % 2);
    pad.sync();
    fake_now_ns += 1'000'000;
    const long before = test::heap_allocations();
    sum += device.exchange({}).velocity.linear_mps.x;
    allocations += test::heap_allocations() - before;
  }
  EXPECT_GT(sum, 0.0);
  EXPECT_EQ(allocations, 0);
}

TEST(EvdevDevice, UnpluggingThrowsDeviceGone) {
  Testbed testbed;
  auto& mouse = testbed.add_input(5, test::spacemouse_compact());
  EvdevDevice device(mouse.path(), velocity_options());
  mouse.send(EV_ABS, ABS_X, 350);
  mouse.sync();
  EXPECT_NEAR(device.exchange({}).velocity.linear_mps.x, 0.1, 1e-12);
  mouse.unplug();
  try {
    device.exchange({});
    ADD_FAILURE() << "exchange() on an unplugged device returned";
  } catch (const DeviceGone& gone) {
    const std::string message = gone.what();
    EXPECT_NE(message.find("/dev/input/event5"), std::string::npos) << message;
    EXPECT_NE(message.find("SpaceMouse Compact"), std::string::npos) << message;
    EXPECT_NE(message.find("is gone: No such device"), std::string::npos) << message;
  }
  device.make_safe();  // nothing to do, and no throw
}

TEST(EvdevDevice, RefusesWhatItCannotDrive) {
  Testbed testbed;
  auto& keyboard = testbed.add_input(2, test::keyboard());
  try {
    EvdevDevice device(keyboard.path());
    ADD_FAILURE() << "a keyboard was taken for a SpaceMouse";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what())
                  .find("/dev/input/event2 (AT Translated Set 2 keyboard) "
                        "is neither a six-axis device"),
              std::string::npos)
        << error.what();
  }
  try {
    EvdevDevice device("/dev/input/event42");
    ADD_FAILURE() << "a missing device opened";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("no input device at /dev/input/event42"),
              std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace afhub::devices
