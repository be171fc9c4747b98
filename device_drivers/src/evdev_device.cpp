#include "afhub/devices/evdev_device.hpp"

#include <fcntl.h>
#include <libevdev/libevdev.h>
#include <linux/input.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <stdexcept>

namespace afhub::devices {
namespace {

constexpr double kMaxStepS = 0.05;  // a stalled loop does not jump the pose

std::int64_t monotonic_ns() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

template <std::size_t N>
void copy_text(std::array<char, N>& to, const char* from) {
  to.fill('\0');
  if (from != nullptr) std::strncpy(to.data(), from, N - 1);
}

double apply_deadband(double x, double band) {
  x = std::clamp(x, -1.0, 1.0);
  const double magnitude = std::fabs(x);
  if (magnitude <= band || band >= 1.0) return 0.0;
  return std::copysign((magnitude - band) / (1.0 - band), x);
}

bool has_all(libevdev* dev, unsigned type, unsigned first, unsigned last) {
  for (unsigned code = first; code <= last; ++code) {
    if (libevdev_has_event_code(dev, type, code) == 0) return false;
  }
  return true;
}

// q <- exp(omega * dt) * q: a rotation by omega (device frame) for dt seconds.
void rotate(Quaternion& q, const Vec3& omega, double dt) {
  const double angle = std::sqrt(omega.x * omega.x + omega.y * omega.y + omega.z * omega.z) * dt;
  if (angle <= 0.0) return;
  const double scale = std::sin(angle / 2.0) / (angle / dt);
  const Quaternion r{omega.x * scale, omega.y * scale, omega.z * scale, std::cos(angle / 2.0)};
  Quaternion out;
  out.w = r.w * q.w - r.x * q.x - r.y * q.y - r.z * q.z;
  out.x = r.w * q.x + r.x * q.w + r.y * q.z - r.z * q.y;
  out.y = r.w * q.y - r.x * q.z + r.y * q.w + r.z * q.x;
  out.z = r.w * q.z + r.x * q.y - r.y * q.x + r.z * q.w;
  const double norm = std::sqrt(out.x * out.x + out.y * out.y + out.z * out.z + out.w * out.w);
  q = {out.x / norm, out.y / norm, out.z / norm, out.w / norm};
}

}  // namespace

EvdevDevice::EvdevDevice(const std::string& path, EvdevOptions options)
    : path_(path), options_(options) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    const int error = errno;
    if (error == EACCES || error == EPERM) {
      throw std::runtime_error("permission denied on " + path +
                               ": install device_drivers/udev/60-afhub.rules (see README) "
                               "and plug the device in again");
    }
    if (error == ENOENT || error == ENODEV || error == ENXIO) {
      throw std::runtime_error("no input device at " + path +
                               ": `afhub device list` shows the devices present");
    }
    throw std::runtime_error("cannot open " + path + ": " + std::strerror(error));
  }
  const int rc = libevdev_new_from_fd(fd_, &dev_);
  if (rc < 0) {
    ::close(fd_);
    throw std::runtime_error(path + " is not an evdev input device: " + std::strerror(-rc));
  }
  const std::string name = libevdev_get_name(dev_) != nullptr ? libevdev_get_name(dev_) : "";

  const bool gamepad = libevdev_has_event_code(dev_, EV_KEY, BTN_SOUTH) != 0;
  relative_ = !gamepad && has_all(dev_, EV_REL, REL_X, REL_RZ);
  const bool six_absolute = has_all(dev_, EV_ABS, ABS_X, ABS_RZ);
  if (!gamepad && !relative_ && !six_absolute) {
    libevdev_free(dev_);
    ::close(fd_);
    throw std::runtime_error(path + " (" + name +
                             ") is neither a six-axis device (SpaceMouse: axes 0..5 as EV_REL "
                             "or EV_ABS) nor a gamepad (BTN_SOUTH)");
  }
  layout_ = gamepad ? EvdevLayout::kGamepad : EvdevLayout::kSixAxis;

  // Buttons: BTN_* codes (0x100 and up) first, then the keyboard-style keys some
  // SpaceMice report, each in code order.
  button_bit_.fill(-1);
  std::uint32_t count = 0;
  auto add_button = [&](unsigned code) {
    if (count < kMaxButtons && libevdev_has_event_code(dev_, EV_KEY, code) != 0) {
      button_codes_[count] = static_cast<std::uint16_t>(code);
      button_bit_[code] = static_cast<std::int8_t>(count);
      ++count;
    }
  };
  for (unsigned code = BTN_MISC; code < kKeyCodes; ++code) add_button(code);
  for (unsigned code = 1; code < BTN_MISC; ++code) add_button(code);

  for (int code = 0; code < kAbsCodes; ++code) {
    const input_absinfo* info = libevdev_get_abs_info(dev_, static_cast<unsigned>(code));
    if (info == nullptr) continue;
    AxisScale& scale = abs_scale_[code];
    scale.centre = (static_cast<double>(info->minimum) + info->maximum) / 2.0;
    scale.half_range = std::max(1.0, (static_cast<double>(info->maximum) - info->minimum) / 2.0);
    scale.flat = info->flat / scale.half_range;
    abs_value_[code] = info->value;
  }

  copy_text(spec_.model, name.c_str());
  copy_text(spec_.serial, libevdev_get_uniq(dev_));
  spec_.workspace_radius_m =
      options_.mode == EvdevAxisMode::kPose ? options_.workspace_radius_m : 0;
  spec_.sensed = kDeviceTranslation | kDeviceRotation;
  spec_.actuated = 0;
  spec_.button_count = count;
}

EvdevDevice::~EvdevDevice() {
  libevdev_free(dev_);
  ::close(fd_);
}

std::int64_t EvdevDevice::now_ns() const {
  return options_.clock_ns != nullptr ? options_.clock_ns() : monotonic_ns();
}

void EvdevDevice::handle_event(std::uint16_t type, std::uint16_t code, std::int32_t value,
                               std::int64_t now) {
  if (type == EV_KEY && code < kKeyCodes && button_bit_[code] >= 0) {
    const std::uint32_t bit = 1U << button_bit_[code];
    buttons_ = value != 0 ? (buttons_ | bit) : (buttons_ & ~bit);
  } else if (type == EV_ABS && code < kAbsCodes) {
    abs_value_[code] = value;
  } else if (type == EV_REL && code <= REL_RZ) {
    rel_pending_[code] = value;
    rel_pending_mask_ |= 1U << code;
  } else if (type == EV_SYN && code == SYN_REPORT && rel_pending_mask_ != 0) {
    // A frame names the nonzero axes of the reports it carries: the other axes of a
    // group it touches are at rest.
    for (int group = 0; group < 2; ++group) {
      const std::uint32_t group_mask = 7U << (3 * group);
      if ((rel_pending_mask_ & group_mask) == 0) continue;
      for (int axis = 3 * group; axis < 3 * group + 3; ++axis) {
        rel_value_[axis] = (rel_pending_mask_ & (1U << axis)) != 0 ? rel_pending_[axis] : 0;
      }
      rel_reported_ns_[group] = now;
    }
    rel_pending_mask_ = 0;
  }
}

double EvdevDevice::abs_deflection(int code) const {
  const AxisScale& scale = abs_scale_[code];
  const double x = (abs_value_[code] - scale.centre) / scale.half_range;
  return apply_deadband(x, std::max(options_.deadband, scale.flat));
}

void EvdevDevice::deflections(std::array<double, 6>& out) const {
  if (layout_ == EvdevLayout::kGamepad) {
    // Triggers rest at their minimum: 0 released, 1 fully pressed.
    auto trigger = [&](int code) { return (abs_deflection(code) + 1.0) / 2.0; };
    out = {abs_deflection(ABS_X),
           -abs_deflection(ABS_Y),  // stick up is negative on evdev
           trigger(ABS_RZ) - trigger(ABS_Z),
           abs_deflection(ABS_HAT0X),
           -abs_deflection(ABS_RY),
           -abs_deflection(ABS_RX)};
    return;
  }
  for (int axis = 0; axis < 6; ++axis) {
    out[axis] = relative_
                    ? apply_deadband(rel_value_[axis] / options_.rel_full_scale, options_.deadband)
                    : abs_deflection(axis);
  }
}

DeviceSample EvdevDevice::exchange(const DeviceOutput& /*output: nothing to actuate*/) {
  const std::int64_t now = now_ns();
  input_event event{};
  unsigned flags = LIBEVDEV_READ_FLAG_NORMAL;
  for (;;) {
    const int rc = libevdev_next_event(dev_, flags, &event);
    if (rc == LIBEVDEV_READ_STATUS_SUCCESS) {
      handle_event(event.type, event.code, event.value, now);
    } else if (rc == LIBEVDEV_READ_STATUS_SYNC) {
      // Events were dropped: libevdev replays the device's state as sync events.
      flags = LIBEVDEV_READ_FLAG_SYNC;
      handle_event(event.type, event.code, event.value, now);
    } else if (rc == -EAGAIN) {
      if (flags == LIBEVDEV_READ_FLAG_NORMAL) break;
      flags = LIBEVDEV_READ_FLAG_NORMAL;  // the sync is over; read on
    } else {
      throw DeviceGone("input device " + path_ + " (" + spec_.model.data() +
                       ") is gone: " + std::strerror(-rc) + "; plug it in again");
    }
  }
  if (relative_) {
    const auto hold_ns = static_cast<std::int64_t>(options_.rel_hold_s * 1e9);
    for (int group = 0; group < 2; ++group) {
      if (now - rel_reported_ns_[group] > hold_ns) {
        std::fill_n(rel_value_.begin() + 3 * group, 3, 0);
      }
    }
  }

  std::array<double, 6> d{};
  deflections(d);
  DeviceSample sample;
  sample.buttons = buttons_;
  sample.velocity.linear_mps = {d[0] * options_.linear_speed_mps, d[1] * options_.linear_speed_mps,
                                d[2] * options_.linear_speed_mps};
  sample.velocity.angular_radps = {d[3] * options_.angular_speed_radps,
                                   d[4] * options_.angular_speed_radps,
                                   d[5] * options_.angular_speed_radps};
  if (options_.mode == EvdevAxisMode::kPose) {
    const double dt =
        first_exchange_ ? 0.0 : std::clamp((now - last_exchange_ns_) * 1e-9, 0.0, kMaxStepS);
    Vec3& p = pose_.position_m;
    const Vec3& v = sample.velocity.linear_mps;
    p = {p.x + v.x * dt, p.y + v.y * dt, p.z + v.z * dt};
    const double reach = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    if (reach > options_.workspace_radius_m) {
      const double shrink = options_.workspace_radius_m / reach;
      p = {p.x * shrink, p.y * shrink, p.z * shrink};
    }
    rotate(pose_.orientation, sample.velocity.angular_radps, dt);
    sample.pose = pose_;
  }
  first_exchange_ = false;
  last_exchange_ns_ = now;
  return sample;
}

}  // namespace afhub::devices
