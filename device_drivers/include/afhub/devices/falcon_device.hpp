// The Novint Falcon as an afhub Device: packets through a FalconTransport (libusb in
// use, scripted in tests), positions by forward kinematics, forces through the
// Jacobian transpose. Device frame (CHAI3D's): origin at the workspace centre, x
// towards the user, y right, z up; metres and newtons.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "afhub/devices/device.hpp"
#include "afhub/devices/falcon_kinematics.hpp"
#include "afhub/devices/falcon_packet.hpp"
#include "afhub/devices/falcon_transport.hpp"
#include "afhub/devices/falcon_usb.hpp"

namespace afhub::devices::falcon {

struct DeviceOptions {
  std::uint8_t leds{kLedGreen};
  double velocity_cutoff_hz{50.0};  // the low-pass on the differenced velocity
  int max_bad_replies{100};         // consecutive missing or malformed replies: gone
};

class FalconDevice final : public Device {
 public:
  FalconDevice(std::unique_ptr<FalconTransport> transport, std::string serial,
               DeviceOptions options = {});
  // Sends a last packet at zero force: however its owner ends (an exception unwinding
  // past the driver's loop), the device is not left pushing.
  ~FalconDevice() override;
  // Opens the Falcon over USB (firmware upload when asked); not homed yet.
  static std::unique_ptr<FalconDevice> open_usb(const UsbOptions& usb, DeviceOptions options = {});

  DeviceSpec spec() const override;
  DeviceSample exchange(const DeviceOutput& output) override;
  void make_safe() noexcept override;

  // Homing: the firmware homes each leg as the user moves the grip all the way out
  // and back in. Exchanges packets (no force) until all three legs report homed or
  // `max_cycles` pass; true when homed. The LEDs show red until then, then `leds`.
  bool home(int max_cycles);

  const Reply& last_reply() const { return last_reply_; }
  // The leg torques applied in the last exchange (after saturation), N m.
  const Vec& last_torques() const { return last_torques_; }

 private:
  // Sends one command, reads and decodes the reply; counts bad replies.
  bool transfer(const Command& command);

  std::unique_ptr<FalconTransport> transport_;
  std::string serial_;
  DeviceOptions options_;
  ForwardSolver solver_;
  Reply last_reply_;
  PacketFault last_fault_;
  bool last_missing_{false};
  int bad_replies_{0};
  Vec position_k_{kWorkspaceCentre};  // kinematic frame
  Vec last_torques_{};
  DeviceSample sample_;
  bool have_position_{false};
  std::chrono::steady_clock::time_point last_time_{};
};

}  // namespace afhub::devices::falcon
