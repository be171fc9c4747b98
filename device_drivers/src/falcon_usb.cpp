#include "afhub/devices/falcon_usb.hpp"

#include <libusb.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "afhub/devices/device.hpp"

namespace afhub::devices::falcon {
namespace {

constexpr unsigned char kOutEndpoint = 0x02;
constexpr unsigned char kInEndpoint = 0x81;
constexpr int kInterface = 0;
constexpr int kUsbPacket = 64;  // full-speed bulk packet
constexpr int kModemBytes = 2;  // the FTDI's status bytes before every IN read
constexpr int kChunk = 62;      // firmware bytes per write: one packet less the status
constexpr unsigned kSetupTimeoutMs = 1000;

// FTDI vendor requests (bmRequestType 0x40, host to device).
constexpr std::uint8_t kFtdiRequestType = 0x40;
constexpr std::uint8_t kReset = 0;
constexpr std::uint8_t kModemControl = 1;
constexpr std::uint8_t kFlowControl = 2;
constexpr std::uint8_t kBaudRate = 3;
constexpr std::uint8_t kDataFormat = 4;
constexpr std::uint8_t kLatencyTimer = 9;
constexpr std::uint16_t kPurgeRx = 1;
constexpr std::uint16_t kPurgeTx = 2;
constexpr std::uint16_t kDtrLow = 0x0100;
constexpr std::uint16_t kDtrHigh = 0x0101;
constexpr std::uint16_t kRtsLow = 0x0200;
constexpr std::uint16_t kBaud9600 = 0x4138;
constexpr std::uint16_t kBaudFirmware = 0x15;
constexpr std::uint16_t kBaudRuntime = 0x2;
constexpr std::uint16_t kEightNOne = 8;

constexpr std::uint8_t kBootProbe[] = {0x0a, 0x43, 0x0d};
constexpr std::uint8_t kBootAnswer[] = {0x0a, 0x44, 0x2c, 0x0d};
constexpr int kBootTries = 100;

// Errors that mean the device is gone or broken for good: the driver must stop.
bool device_lost(int code) {
  return code == LIBUSB_ERROR_NO_DEVICE || code == LIBUSB_ERROR_IO || code == LIBUSB_ERROR_PIPE ||
         code == LIBUSB_ERROR_OVERFLOW || code == LIBUSB_ERROR_NOT_FOUND ||
         code == LIBUSB_ERROR_TIMEOUT;
}

[[noreturn]] void fail(int code, const char* what) {
  std::string text = std::string("Novint Falcon: ") + what + " failed: " + libusb_error_name(code) +
                     " (" + libusb_strerror(static_cast<libusb_error>(code)) + ")";
  if (device_lost(code)) {
    throw DeviceGone(text +
                     ": the Falcon was unplugged or stopped answering; plug it in "
                     "and start the driver again");
  }
  throw std::runtime_error(text);
}

struct Found {
  libusb_device_handle* handle{nullptr};
  std::string serial;
};

std::string read_serial(libusb_device_handle* handle, std::uint8_t index) {
  if (index == 0) return {};
  unsigned char text[128] = {};
  const int length = libusb_get_string_descriptor_ascii(handle, index, text, sizeof text - 1);
  if (length < 0) return {};
  return std::string(reinterpret_cast<const char*>(text), static_cast<std::size_t>(length));
}

Found find(libusb_context* context, const std::string& wanted_serial) {
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(context, &list);
  if (count < 0) fail(static_cast<int>(count), "listing USB devices");
  Found found;
  std::string seen;     // serials of the Falcons not chosen
  std::string refused;  // Falcons this user may not open
  for (ssize_t i = 0; i < count && found.handle == nullptr; ++i) {
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(list[i], &descriptor) != 0) continue;
    if (descriptor.idVendor != kVendorId || descriptor.idProduct != kProductId) continue;
    libusb_device_handle* handle = nullptr;
    const int opened = libusb_open(list[i], &handle);
    const std::string where = "bus " + std::to_string(libusb_get_bus_number(list[i])) + " device " +
                              std::to_string(libusb_get_device_address(list[i]));
    if (opened != 0) {
      refused += (refused.empty() ? "" : ", ") + where + " (" + libusb_error_name(opened) + ")";
      continue;
    }
    std::string serial = read_serial(handle, descriptor.iSerialNumber);
    if (!wanted_serial.empty() && serial != wanted_serial) {
      seen += (seen.empty() ? "" : ", ") + (serial.empty() ? where : serial);
      libusb_close(handle);
      continue;
    }
    found = {handle, serial};
  }
  libusb_free_device_list(list, 1);
  if (found.handle != nullptr) return found;
  std::string text = "Novint Falcon: no Falcon (USB 0403:cb48)";
  if (!wanted_serial.empty()) text += " with serial '" + wanted_serial + "'";
  text += " found";
  if (!seen.empty()) text += "; Falcons present: " + seen;
  if (!refused.empty()) {
    text += "; could not open " + refused +
            ": permission denied? Install the udev rules (see README, \"Devices\") or run "
            "as root";
  } else if (seen.empty()) {
    text += ": is it plugged in and powered?";
  }
  throw std::runtime_error(text);
}

bool ends_with_boot_answer(const std::uint8_t* payload, int length) {
  constexpr int kAnswer = sizeof kBootAnswer;
  // Linux reads the four bytes alone; macOS has a 0x00 before them.
  if (length < kAnswer) return false;
  for (int i = 0; i < length - kAnswer; ++i) {
    if (payload[i] != 0) return false;
  }
  return std::memcmp(payload + length - kAnswer, kBootAnswer, kAnswer) == 0;
}

}  // namespace

std::vector<std::uint8_t> read_firmware(const std::string& path) {
  const std::string advice =
      ": give the Falcon firmware image from your Novint or libnifalcon installation "
      "(afhub cannot ship it)";
  std::error_code ignored;
  if (std::filesystem::is_directory(path, ignored)) {
    throw std::runtime_error("Novint Falcon firmware '" + path + "' is a directory" + advice);
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    throw std::runtime_error("Novint Falcon firmware '" + path +
                             "' cannot be read: " + std::strerror(errno) + advice);
  }
  std::vector<std::uint8_t> image((std::istreambuf_iterator<char>(file)),
                                  std::istreambuf_iterator<char>());
  if (file.bad()) {
    throw std::runtime_error("Novint Falcon firmware '" + path + "' cannot be read" + advice);
  }
  if (image.size() < kMinFirmwareBytes || image.size() > kMaxFirmwareBytes) {
    throw std::runtime_error("Novint Falcon firmware '" + path + "' has " +
                             std::to_string(image.size()) + " bytes; a firmware image has " +
                             std::to_string(kMinFirmwareBytes) + " to " +
                             std::to_string(kMaxFirmwareBytes) + advice);
  }
  return image;
}

FalconUsb::FalconUsb(libusb_context* context, libusb_device_handle* handle, std::string serial,
                     std::chrono::milliseconds reply_timeout)
    : context_(context),
      handle_(handle),
      serial_(std::move(serial)),
      reply_timeout_(reply_timeout) {}

FalconUsb::~FalconUsb() {
  libusb_release_interface(handle_, kInterface);
  libusb_close(handle_);
  libusb_exit(context_);
}

std::unique_ptr<FalconUsb> FalconUsb::open(const UsbOptions& options) {
  // A bad firmware file fails before the device is touched.
  std::vector<std::uint8_t> image;
  if (!options.firmware_path.empty()) image = read_firmware(options.firmware_path);

  libusb_context* context = nullptr;
  const int initialised = libusb_init(&context);
  if (initialised != 0) fail(initialised, "starting libusb");
  Found found;
  try {
    found = find(context, options.serial);
  } catch (...) {
    libusb_exit(context);
    throw;
  }
  if (libusb_kernel_driver_active(found.handle, kInterface) == 1) {
    libusb_detach_kernel_driver(found.handle, kInterface);
  }
  const int claimed = libusb_claim_interface(found.handle, kInterface);
  if (claimed != 0) {
    libusb_close(found.handle);
    libusb_exit(context);
    fail(claimed, "claiming the Falcon's interface (is another driver using it?)");
  }
  std::unique_ptr<FalconUsb> usb(
      new FalconUsb(context, found.handle, found.serial, options.reply_timeout));
  usb->purge();
  usb->set_normal_mode();
  if (!image.empty()) usb->load_firmware(image);

  // The firmware answers a packet with a packet; the bootloader does not.
  const Packet idle = encode(Command{});
  for (int attempt = 0; attempt < 10; ++attempt) {
    const TransportReply reply = usb->exchange(idle);
    if (reply.received && decode_reply(reply.packet).ok()) return usb;
  }
  throw std::runtime_error(
      "Novint Falcon: the firmware does not answer; load it with the firmware option "
      "(--firmware FILE, the image from your Novint or libnifalcon installation)");
}

void FalconUsb::control(std::uint8_t request, std::uint16_t value, const char* what) {
  const int rc = libusb_control_transfer(handle_, kFtdiRequestType, request, value, 0, nullptr, 0,
                                         kSetupTimeoutMs);
  if (rc < 0) fail(rc, what);
}

void FalconUsb::write(const std::uint8_t* data, int length, const char* what) {
  int sent = 0;
  const int rc = libusb_bulk_transfer(handle_, kOutEndpoint, const_cast<std::uint8_t*>(data),
                                      length, &sent, kSetupTimeoutMs);
  if (rc != 0) fail(rc, what);
  if (sent != length) fail(LIBUSB_ERROR_IO, what);
}

int FalconUsb::read(std::uint8_t* payload, int capacity, unsigned timeout_ms, const char* what) {
  std::uint8_t buffer[kUsbPacket];
  int got = 0;
  const int rc = libusb_bulk_transfer(handle_, kInEndpoint, buffer, kUsbPacket, &got,
                                      std::max(1U, timeout_ms));
  if (rc != 0 && rc != LIBUSB_ERROR_TIMEOUT) fail(rc, what);
  const int length = std::min(std::max(got - kModemBytes, 0), capacity);
  if (length > 0) std::memcpy(payload, buffer + kModemBytes, static_cast<std::size_t>(length));
  return length;
}

void FalconUsb::purge() {
  control(kReset, kPurgeRx, "purging the receive buffer");
  control(kReset, kPurgeTx, "purging the send buffer");
}

void FalconUsb::set_normal_mode() {
  control(kLatencyTimer, 1, "setting the latency timer");
  control(kBaudRate, kBaudRuntime, "setting the baud rate");
  purge();
}

void FalconUsb::load_firmware(const std::vector<std::uint8_t>& image) {
  purge();
  control(kLatencyTimer, 16, "setting the latency timer");
  control(kBaudRate, kBaud9600, "setting the baud rate");
  control(kDataFormat, kEightNOne, "setting 8N1");
  control(kFlowControl, 0, "turning flow control off");
  control(kModemControl, kRtsLow, "setting RTS low");
  control(kModemControl, kDtrLow, "setting DTR low");
  control(kModemControl, kDtrHigh, "setting DTR high");

  std::uint8_t answer[kUsbPacket];
  bool booted = false;
  for (int attempt = 0; attempt < kBootTries && !booted; ++attempt) {
    write(kBootProbe, sizeof kBootProbe, "sending the bootloader probe");
    booted = ends_with_boot_answer(
        answer, read(answer, sizeof answer, kSetupTimeoutMs, "reading the bootloader's answer"));
  }
  if (!booted) {
    throw std::runtime_error(
        "Novint Falcon: the bootloader did not answer the firmware handshake (0a 43 0d sent " +
        std::to_string(kBootTries) +
        " times): unplug the Falcon's power and USB, plug them in again, and retry");
  }
  control(kModemControl, kDtrLow, "setting DTR low");
  control(kBaudRate, kBaudFirmware, "setting the firmware baud rate");
  const std::uint8_t start = 'A';
  write(&start, 1, "starting the firmware upload");
  const int echoed = read(answer, sizeof answer, kSetupTimeoutMs, "reading the upload's start");
  if (echoed != 1 || answer[0] != start) {
    throw std::runtime_error(
        "Novint Falcon: the bootloader did not echo 'A' to start the upload: power-cycle the "
        "Falcon and retry");
  }

  for (std::size_t offset = 0; offset < image.size(); offset += kChunk) {
    const int length = static_cast<int>(std::min<std::size_t>(kChunk, image.size() - offset));
    write(image.data() + offset, length, "uploading the firmware");
    int checked = 0;
    int idle_reads = 0;
    while (checked < length) {
      const int got =
          read(answer, length - checked, kSetupTimeoutMs, "reading the firmware's echo");
      if (got == 0 && ++idle_reads > 100) {
        throw std::runtime_error("Novint Falcon: no echo of firmware byte " +
                                 std::to_string(offset + checked) +
                                 ": power-cycle the Falcon and retry");
      }
      for (int i = 0; i < got; ++i) {
        const std::size_t at = offset + static_cast<std::size_t>(checked + i);
        if (answer[i] != image[at]) {
          throw std::runtime_error("Novint Falcon: firmware byte " + std::to_string(at) +
                                   " echoed as " + std::to_string(answer[i]) + ", sent " +
                                   std::to_string(image[at]) +
                                   ": the upload is corrupt; power-cycle the Falcon and retry");
        }
      }
      checked += got;
    }
  }
  set_normal_mode();
}

TransportReply FalconUsb::exchange(const Packet& command) {
  write(command.data(), static_cast<int>(command.size()), "sending a packet");
  // The reply may come in pieces; keep the newest complete '<' ... '>' frame.
  std::uint8_t pending[4 * kPacketSize + kUsbPacket];
  int have = 0;
  TransportReply out;
  const auto deadline = std::chrono::steady_clock::now() + reply_timeout_;
  for (;;) {
    if (have > static_cast<int>(sizeof pending) - kUsbPacket) {
      // Out of step: keep only what could start the next frame.
      const int keep = static_cast<int>(kPacketSize) - 1;
      std::memmove(pending, pending + have - keep, static_cast<std::size_t>(keep));
      have = keep;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    have += read(pending + have, static_cast<int>(sizeof pending) - have,
                 static_cast<unsigned>(std::max<long>(1, left.count())), "reading a packet");
    for (int start = have - static_cast<int>(kPacketSize); start >= 0; --start) {
      if (pending[start] == '<' && pending[start + kPacketSize - 1] == '>') {
        std::memcpy(out.packet.data(), pending + start, kPacketSize);
        out.received = true;
        return out;
      }
    }
    if (std::chrono::steady_clock::now() >= deadline) break;
  }
  // No frame: hand back what came, so that decoding says what is wrong with it.
  if (have >= static_cast<int>(kPacketSize)) {
    std::memcpy(out.packet.data(), pending + have - kPacketSize, kPacketSize);
    out.received = true;
  }
  return out;
}

}  // namespace afhub::devices::falcon
