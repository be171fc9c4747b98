// The Falcon over libusb-1.0: its FTDI bridge (VID:PID 0403:cb48, interface 0, bulk
// OUT 0x02, bulk IN 0x81, two modem-status bytes before every IN read), the firmware
// upload and the 16-byte exchange. The firmware image is Novint's and never ships:
// the user names their own file.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "afhub/devices/falcon_transport.hpp"

struct libusb_context;
struct libusb_device_handle;

namespace afhub::devices::falcon {

inline constexpr std::uint16_t kVendorId = 0x0403;
inline constexpr std::uint16_t kProductId = 0xcb48;
// The bounds a Falcon firmware image can have (Novint's images are a few KiB).
inline constexpr std::size_t kMinFirmwareBytes = 1024;
inline constexpr std::size_t kMaxFirmwareBytes = 64 * 1024;

struct UsbOptions {
  std::string serial;         // empty: the first Falcon found
  std::string firmware_path;  // empty: the firmware must be running already
  std::chrono::milliseconds reply_timeout{20};
};

// Reads a firmware image; a missing, unreadable or wrongly sized file is a
// std::runtime_error naming the path and what to do.
std::vector<std::uint8_t> read_firmware(const std::string& path);

class FalconUsb final : public FalconTransport {
 public:
  // Finds and opens the Falcon, sets the FTDI up, uploads the firmware when
  // `options.firmware_path` is set, and checks that the firmware answers. Errors are
  // std::runtime_error with what to do (not found, permission, firmware refused).
  static std::unique_ptr<FalconUsb> open(const UsbOptions& options);
  ~FalconUsb() override;
  FalconUsb(const FalconUsb&) = delete;
  FalconUsb& operator=(const FalconUsb&) = delete;

  TransportReply exchange(const Packet& command) override;
  const std::string& serial() const { return serial_; }

  // The firmware upload: bootloader handshake, then the image in 62-byte chunks,
  // each echoed back and compared. Throws std::runtime_error or DeviceGone.
  void load_firmware(const std::vector<std::uint8_t>& image);

 private:
  FalconUsb(libusb_context* context, libusb_device_handle* handle, std::string serial,
            std::chrono::milliseconds reply_timeout);
  void control(std::uint8_t request, std::uint16_t value, const char* what);
  void write(const std::uint8_t* data, int length, const char* what);
  // One IN read; returns the payload bytes (modem-status bytes stripped).
  int read(std::uint8_t* payload, int capacity, unsigned timeout_ms, const char* what);
  void purge();
  void set_normal_mode();

  libusb_context* context_;
  libusb_device_handle* handle_;
  std::string serial_;
  std::chrono::milliseconds reply_timeout_;
};

}  // namespace afhub::devices::falcon
