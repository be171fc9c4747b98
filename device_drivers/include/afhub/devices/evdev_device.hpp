// An evdev input device as a Device: a 3Dconnexion SpaceMouse (six axes, EV_REL or
// EV_ABS codes 0..5) or a gamepad (the Linux gamepad specification), read through
// libevdev. It senses and never actuates: the force in exchange() is ignored.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "afhub/devices/device.hpp"

struct libevdev;

namespace afhub::devices {

enum class EvdevAxisMode {
  kPose,      // the axes drive a pose, integrated and kept within the workspace radius
  kVelocity,  // the axes are a velocity only; the pose stays at the origin
};

// How the six deflections (each in [-1, 1]) become motion.
struct EvdevOptions {
  EvdevAxisMode mode{EvdevAxisMode::kPose};
  double linear_speed_mps{0.1};     // at full deflection
  double angular_speed_radps{1.0};  // at full deflection
  double workspace_radius_m{0.1};   // kPose: the position stays within this sphere
  double deadband{0.05};            // fraction of full deflection read as rest
  // EV_REL devices (older SpaceMice) report the deflection as a count, and the
  // kernel drops zero counts, so a released cap sends nothing: the axes return to
  // rest after rel_hold_s without a report.
  double rel_full_scale{350.0};
  double rel_hold_s{0.1};
  // Monotonic time in ns (CLOCK_MONOTONIC when null); tests drive their own.
  std::int64_t (*clock_ns)(){nullptr};
};

enum class EvdevLayout {
  kSixAxis,  // SpaceMouse: x y z, rx ry rz
  kGamepad,  // left stick x/y, triggers z, right stick yaw/pitch, d-pad roll
};

class EvdevDevice final : public Device {
 public:
  // Opens `path` (/dev/input/eventN) without blocking. Throws std::runtime_error
  // naming the path and what to do: no such device, no permission (the udev
  // rules), or not a six-axis device nor a gamepad.
  explicit EvdevDevice(const std::string& path, EvdevOptions options = {});
  ~EvdevDevice() override;
  EvdevDevice(const EvdevDevice&) = delete;
  EvdevDevice& operator=(const EvdevDevice&) = delete;

  DeviceSpec spec() const override { return spec_; }
  // Reads every pending event, then returns the deflections as motion. Throws
  // DeviceGone when the device went away (ENODEV, or any read error).
  DeviceSample exchange(const DeviceOutput& output) override;
  void make_safe() noexcept override {}

  EvdevLayout layout() const { return layout_; }
  // Bit i of DeviceSample::buttons is button_code(i): the device's keys, BTN_*
  // codes first, each range in code order.
  std::uint16_t button_code(std::uint32_t bit) const { return button_codes_[bit]; }

  static constexpr std::uint32_t kMaxButtons = 32;

 private:
  struct AxisScale {
    double centre{0.0};
    double half_range{1.0};
    double flat{0.0};  // the device's own dead zone, as a fraction
  };
  static constexpr int kAbsCodes = 0x40;   // ABS_CNT
  static constexpr int kKeyCodes = 0x300;  // KEY_CNT

  void handle_event(std::uint16_t type, std::uint16_t code, std::int32_t value, std::int64_t now);
  double abs_deflection(int code) const;
  void deflections(std::array<double, 6>& out) const;
  std::int64_t now_ns() const;

  std::string path_;
  EvdevOptions options_;
  int fd_{-1};
  libevdev* dev_{nullptr};
  EvdevLayout layout_{EvdevLayout::kSixAxis};
  bool relative_{false};
  DeviceSpec spec_{};

  std::array<std::uint16_t, kMaxButtons> button_codes_{};
  std::array<std::int8_t, kKeyCodes> button_bit_{};  // -1: not a button we report
  std::uint32_t buttons_{0};

  std::array<AxisScale, kAbsCodes> abs_scale_{};
  std::array<std::int32_t, kAbsCodes> abs_value_{};
  // EV_REL: counts of the current frame, the values in force, and when each group
  // (translation 0..2, rotation 3..5) last reported.
  std::array<std::int32_t, 6> rel_pending_{};
  std::uint32_t rel_pending_mask_{0};
  std::array<std::int32_t, 6> rel_value_{};
  std::array<std::int64_t, 2> rel_reported_ns_{};

  Pose pose_{};
  std::int64_t last_exchange_ns_{0};
  bool first_exchange_{true};
};

}  // namespace afhub::devices
