#include "afhub/devices/falcon_device.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace afhub::devices::falcon {
namespace {

// Kinematic frame (x right, y up, z towards the user, origin at the base) to the device
// frame (x towards the user, y right, z up, origin at the workspace centre), and back
// for forces.
Vec3 to_device(const Vec& k) {
  return {k[2] - kWorkspaceCentre[2], k[0] - kWorkspaceCentre[0], k[1] - kWorkspaceCentre[1]};
}
Vec force_to_kinematic(const Vec3& f) {
  return {f.y, f.z, f.x};
}

template <std::size_t N>
void copy_text(std::array<char, N>& to, const std::string& from) {
  const std::size_t length = std::min(from.size(), N - 1);
  std::copy_n(from.begin(), length, to.begin());
  to[length] = '\0';
}

}  // namespace

FalconDevice::FalconDevice(std::unique_ptr<FalconTransport> transport, std::string serial,
                           DeviceOptions options)
    : transport_(std::move(transport)), serial_(std::move(serial)), options_(options) {}

std::unique_ptr<FalconDevice> FalconDevice::open_usb(const UsbOptions& usb, DeviceOptions options) {
  auto transport = FalconUsb::open(usb);
  std::string serial = transport->serial();
  return std::make_unique<FalconDevice>(std::move(transport), std::move(serial), options);
}

DeviceSpec FalconDevice::spec() const {
  DeviceSpec spec;
  copy_text(spec.model, "Novint Falcon");
  copy_text(spec.serial, serial_);
  spec.max_force_n = 8.0;  // CHAI3D's figures for the Falcon
  spec.max_stiffness_npm = 3000.0;
  spec.workspace_radius_m = 0.04;
  spec.sensed = kDeviceTranslation;
  spec.actuated = kDeviceTranslation;
  spec.button_count = 4;
  return spec;
}

bool FalconDevice::transfer(const Command& command) {
  const TransportReply reply = transport_->exchange(encode(command));
  if (reply.received) {
    const DecodedReply decoded = decode_reply(reply.packet);
    if (decoded.ok()) {
      last_reply_ = decoded.reply;
      bad_replies_ = 0;
      return true;
    }
    last_fault_ = decoded.fault;
  }
  last_missing_ = !reply.received;
  if (++bad_replies_ >= options_.max_bad_replies) {
    const std::string count = std::to_string(bad_replies_);
    throw DeviceGone(last_missing_
                         ? "Novint Falcon: no reply to " + count +
                               " packets in a row: the Falcon stopped answering; power-cycle "
                               "it and start the driver again"
                         : "Novint Falcon: " + count +
                               " malformed replies in a row, the last: " + describe(last_fault_) +
                               ": power-cycle the Falcon and start the driver again");
  }
  return false;
}

DeviceSample FalconDevice::exchange(const DeviceOutput& output) {
  Command command;
  command.leds = options_.leds;
  const auto torques = force_to_torques(position_k_, force_to_kinematic(output.wrench.force_n));
  last_torques_ = torques ? torques->torque_nm : Vec{};
  command.motors = torques_to_motors(last_torques_);
  if (!transfer(command)) return sample_;

  LegAngles angles{};
  for (std::size_t leg = 0; leg < 3; ++leg) {
    angles[leg] = encoder_to_angle(last_reply_.encoders[leg]);
  }
  sample_.buttons = last_reply_.grip_buttons;
  const auto now = std::chrono::steady_clock::now();
  const auto solved = solver_.solve(angles);
  if (!solved) return sample_;  // encoders no leg pose explains (not homed): keep the last

  const Vec3 position = to_device(*solved);
  if (have_position_) {
    const double dt = std::chrono::duration<double>(now - last_time_).count();
    if (dt > 0.0) {
      // Differenced, then low-passed: encoder steps are coarse at 1 kHz.
      const double tau = 1.0 / (2.0 * std::numbers::pi * options_.velocity_cutoff_hz);
      const double alpha = dt / (dt + tau);
      const Vec3& previous = sample_.pose.position_m;
      Vec3& velocity = sample_.velocity.linear_mps;
      velocity.x += alpha * ((position.x - previous.x) / dt - velocity.x);
      velocity.y += alpha * ((position.y - previous.y) / dt - velocity.y);
      velocity.z += alpha * ((position.z - previous.z) / dt - velocity.z);
    }
  }
  position_k_ = *solved;
  sample_.pose.position_m = position;
  have_position_ = true;
  last_time_ = now;
  return sample_;
}

FalconDevice::~FalconDevice() {
  if (transport_) make_safe();
}

void FalconDevice::make_safe() noexcept {
  try {
    Command idle;
    idle.leds = options_.leds;
    transport_->exchange(encode(idle));
    last_torques_ = {};
  } catch (...) {
    // The device is gone: it applies no force without packets.
  }
}

bool FalconDevice::home(int max_cycles) {
  Command homing;
  homing.homing = true;
  homing.leds = kLedRed;
  for (int cycle = 0; cycle < max_cycles; ++cycle) {
    if (transfer(homing) && (last_reply_.homed & kAllHomed) == kAllHomed) {
      // The encoders now count from home: forget the old pose.
      solver_.reset();
      have_position_ = false;
      sample_ = DeviceSample{};
      Command done;
      done.leds = options_.leds;
      transfer(done);
      return true;
    }
  }
  return false;
}

}  // namespace afhub::devices::falcon
