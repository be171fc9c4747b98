// The driver loop on a hub, with a device that goes away: the driver says so and exits
// 1, or with `reconnect` waits until the device opens again and carries on; on a stop
// its last state is published at zero force and the device is made safe.
#include "afhub/devices/driver_loop.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "afhub/hub/channel.hpp"
#include "afhub/shm_layout/channel_names.hpp"

namespace afhub::devices {
namespace {

// A device that goes away after `lifetime` exchanges (never, when 0), and counts.
struct Counts {
  std::atomic<int> opens{0}, exchanges{0}, made_safe{0};
  double last_force_z = -1.0;  // of the last output the device received
  double max_force_z = 0.0;
};

class FleetingDevice : public Device {
 public:
  FleetingDevice(Counts& counts, int lifetime) : counts_(counts), lifetime_(lifetime) {}
  DeviceSpec spec() const override {
    DeviceSpec spec;
    spec.max_force_n = 5.0;
    return spec;
  }
  DeviceSample exchange(const DeviceOutput& output) override {
    if (lifetime_ > 0 && ++exchanged_ > lifetime_) throw DeviceGone("unplugged (test)");
    ++counts_.exchanges;
    counts_.last_force_z = output.wrench.force_n.z;
    counts_.max_force_z = std::max(counts_.max_force_z, output.wrench.force_n.z);
    return {};
  }
  void make_safe() noexcept override { ++counts_.made_safe; }

 private:
  Counts& counts_;
  int lifetime_;
  int exchanged_ = 0;
};

DriverOptions options_for(const std::string& name) {
  DriverOptions options;
  options.name = name;
  options.survive_hub_loss = false;
  options.wait_s = 0.0;
  return options;
}

TEST(DriverLoop, ADeviceThatGoesAwayEndsTheDriverWithExitCode1) {
  Counts counts;
  const int code = run_driver(
      [&] {
        ++counts.opens;
        return std::make_unique<FleetingDevice>(counts, 50);
      },
      options_for("fleeting"));
  EXPECT_EQ(code, 1);
  EXPECT_EQ(counts.opens, 1);
  EXPECT_EQ(counts.exchanges, 50);
  EXPECT_EQ(counts.made_safe, 1);
}

TEST(DriverLoop, WithReconnectItWaitsForTheDeviceAndCarriesOn) {
  Counts counts;
  DriverOptions options = options_for("returning");
  options.reconnect = true;
  options.loop.max_cycles = 200;  // per opened device: the second one ends the run
  const int code = run_driver(
      [&]() -> std::unique_ptr<Device> {
        const int open = ++counts.opens;
        if (open == 2 || open == 3) throw DeviceGone("still unplugged (test)");
        return std::make_unique<FleetingDevice>(counts, open == 1 ? 20 : 0);
      },
      options);
  EXPECT_EQ(code, 0);
  EXPECT_EQ(counts.opens, 4);
  EXPECT_EQ(counts.exchanges, 20 + 200 + 1);  // the last one at zero force, on the stop
}

// A device whose transport fails with an error it does not list (a libusb error other
// than "gone") once, mid-cycle, while it pushes.
class FailingDevice : public FleetingDevice {
 public:
  FailingDevice(Counts& counts, int fail_at) : FleetingDevice(counts, 0), fail_at_(fail_at) {}
  DeviceSample exchange(const DeviceOutput& output) override {
    if (++calls_ == fail_at_) throw std::runtime_error("LIBUSB_ERROR_OTHER (test)");
    return FleetingDevice::exchange(output);
  }

 private:
  int fail_at_;
  int calls_ = 0;
};

// Commands the device to push 3 N up, the command fresh for a second, with no ramp.
void push_3n(Writer<DeviceCommand>& commands, DriverOptions& options) {
  options.safety.ramp_s = 0.0;
  options.safety.watchdog_ns = 1'000'000'000;
  DeviceCommand* command = commands.loan();
  ASSERT_NE(command, nullptr);
  command->wrench.force_n = {0.0, 0.0, 3.0};
  command->enable = 1;
  commands.publish(command);
}

TEST(DriverLoop, AnUnlistedDeviceErrorZeroesTheForceMakesSafeAndEndsWithExitCode1) {
  Counts counts;
  LatestReader<DeviceState> states(body_state_channel(device_channel_name("failing")));
  Writer<DeviceCommand> commands(body_command_channel(device_channel_name("failing")));
  DriverOptions options = options_for("failing");
  push_3n(commands, options);
  const int code = run_driver(
      [&] {
        ++counts.opens;
        return std::make_unique<FailingDevice>(counts, 100);
      },
      options);
  EXPECT_EQ(code, 1);
  EXPECT_EQ(counts.max_force_z, 3.0);   // it was pushing
  EXPECT_EQ(counts.exchanges, 99 + 1);  // and the last one, at zero force
  EXPECT_EQ(counts.last_force_z, 0.0);
  EXPECT_EQ(counts.made_safe, 1);
  const DeviceState* last = states.latest();
  ASSERT_NE(last, nullptr);
  EXPECT_EQ(last->gate, ForceGate::kStopping);
  EXPECT_EQ(last->applied.force_n.z, 0.0);
}

TEST(DriverLoop, OnAStopTheLastStateIsAtZeroForce) {
  Counts counts;
  LatestReader<DeviceState> states(body_state_channel(device_channel_name("stopping")));
  Writer<DeviceCommand> commands(body_command_channel(device_channel_name("stopping")));
  DriverOptions options = options_for("stopping");
  options.loop.max_cycles = 300;
  push_3n(commands, options);
  const int code = run_driver(
      [&] {
        ++counts.opens;
        return std::make_unique<FleetingDevice>(counts, 0);
      },
      options);
  EXPECT_EQ(code, 0);
  EXPECT_EQ(counts.made_safe, 1);
  const DeviceState* last = states.latest();
  ASSERT_NE(last, nullptr);
  EXPECT_EQ(last->gate, ForceGate::kStopping);
  EXPECT_EQ(last->applied.force_n.z, 0.0);
}

// A reading gone wrong: every other sample's position is not a number.
class GlitchyDevice : public FleetingDevice {
 public:
  using FleetingDevice::FleetingDevice;
  DeviceSample exchange(const DeviceOutput& output) override {
    DeviceSample sample = FleetingDevice::exchange(output);
    if (++exchanged_ % 2 == 0) sample.pose.position_m.x = std::nan("");
    return sample;
  }

 private:
  int exchanged_ = 0;
};

TEST(DriverLoop, ASampleThatIsNotFiniteIsNotPublishedAndSaid) {
  Counts counts;
  LatestReader<DeviceState> states(body_state_channel(device_channel_name("glitchy")));
  DriverOptions options = options_for("glitchy");
  options.loop.max_cycles = 200;
  ::testing::internal::CaptureStderr();
  const int code = run_driver([&] { return std::make_unique<GlitchyDevice>(counts, 0); }, options);
  const std::string said = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, 0);
  const DeviceState* last = states.latest();
  ASSERT_NE(last, nullptr) << "readers refuse a state that is not finite: none came";
  EXPECT_TRUE(std::isfinite(last->pose.position_m.x));
  // 200 cycles and the last one at zero force: the 100 finite samples published.
  EXPECT_EQ(counts.exchanges, 201);
  EXPECT_EQ(last->header.sequence, 101U);
  EXPECT_NE(said.find("afhub device glitchy: 1 sample of the device not published: "
                      "DeviceState.pose is not a finite number"),
            std::string::npos)
      << said;
}

}  // namespace
}  // namespace afhub::devices
