// What a driver process needs from one device, whatever its transport: the loop in
// driver_loop.hpp calls exchange() once per cycle and owns every safety rule
// (watchdog, clamp, ramp, zero on exit), so a device only moves bytes.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

#include "afhub/shm_layout/device.hpp"

namespace afhub::devices {

// One reading of the device, in its own frame (metres, radians, seconds).
struct DeviceSample {
  Pose pose;
  Twist velocity;
  double gripper_angle_rad{0.0};
  std::uint32_t buttons{0};
};

// The force to apply this cycle, already clamped and ramped by the loop.
struct DeviceOutput {
  Wrench wrench;
  double gripper_force_n{0.0};
};

// The device went away (unplugged, ENODEV, a USB error it cannot recover from).
struct DeviceGone : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Device {
 public:
  virtual ~Device() = default;
  virtual DeviceSpec spec() const = 0;
  // Applies `output` and returns the newest sample. Called once per cycle from the
  // loop's thread; must not allocate. Throws DeviceGone when the device is lost.
  virtual DeviceSample exchange(const DeviceOutput& output) = 0;
  // Zero force now: the last call before the process exits or gives the device up.
  virtual void make_safe() noexcept = 0;
};

}  // namespace afhub::devices
