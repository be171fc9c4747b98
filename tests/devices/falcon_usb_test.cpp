// The Falcon's libusb transport, the real driver code over the real libusb, against an
// emulated device: umockdev adds a Falcon (0403:cb48) to a fake sysfs and answers the
// usbdevfs ioctls of its /dev/bus/usb node in-process, as libusb's own tests do. Each
// test scripts the URBs the driver must submit, in order, and what the device answers:
// the FTDI set-up, the bootloader handshake, the firmware upload with its echoes, one
// packet exchange, and unplugging. Runs under umockdev-wrapper (see CMakeLists.txt).
#include <gtest/gtest.h>

#include <linux/ioctl.h>
#include <linux/usbdevice_fs.h>
#include <umockdev.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <vector>

#include "afhub/devices/device.hpp"
#include "afhub/devices/falcon_device.hpp"
#include "afhub/devices/falcon_usb.hpp"

namespace afhub::devices::falcon {
namespace {

using Bytes = std::vector<std::uint8_t>;

// One URB the driver must submit, and the device's answer.
struct Step {
  std::uint8_t type;      // USBDEVFS_URB_TYPE_CONTROL or _BULK
  std::uint8_t endpoint;  // 0 for control
  Bytes sent;             // control: the 8-byte setup; bulk OUT: the data
  Bytes answer;           // bulk IN: what the device returns (modem bytes included)
  int submit_errno{0};    // the submit fails with this (ENODEV: unplugged)
  int reap_status{0};     // the URB completes with this status (-EPROTO: a bus error)
};

Step ftdi(std::uint8_t request, std::uint16_t value) {
  return {USBDEVFS_URB_TYPE_CONTROL,
          0,
          Bytes{0x40, request, static_cast<std::uint8_t>(value & 0xff),
                static_cast<std::uint8_t>(value >> 8), 0, 0, 0, 0},
          {}};
}
Step out(Bytes data) {
  return {USBDEVFS_URB_TYPE_BULK, 0x02, std::move(data), {}};
}
// An IN read: the FTDI's two modem-status bytes, then `payload`.
Step in(const Bytes& payload) {
  Bytes answer{0x31, 0x60};
  answer.insert(answer.end(), payload.begin(), payload.end());
  return {USBDEVFS_URB_TYPE_BULK, 0x81, {}, answer};
}
Bytes bytes(const Packet& packet) {
  return Bytes(packet.begin(), packet.end());
}

std::string hex(const std::uint8_t* data, std::size_t length) {
  std::string text;
  char byte[4];
  for (std::size_t i = 0; i < length; ++i) {
    std::snprintf(byte, sizeof byte, "%02x ", data[i]);
    text += byte;
  }
  return text;
}

// The Falcon's descriptors: device (serial string 3), one configuration, interface 0
// with bulk IN 0x81 and bulk OUT 0x02.
constexpr const char* kFalconSysfs =
    "P: /devices/usb1\n"
    "N: bus/usb/001/001\n"
    "E: SUBSYSTEM=usb\n"
    "E: DRIVER=usb\n"
    "E: BUSNUM=001\n"
    "E: DEVNUM=001\n"
    "E: DEVNAME=/dev/bus/usb/001/001\n"
    "E: DEVTYPE=usb_device\n"
    "A: bConfigurationValue=1\\n\n"
    "A: busnum=1\\n\n"
    "A: devnum=1\\n\n"
    "A: speed=12\\n\n"
    "H: descriptors="
    "12010002000000400304"
    "48cb0006010203010902"
    "20000101008032090400"
    "0002ffffff0207058102"
    "40000007050202400000\n";
constexpr const char* kSerial = "FTB3WL6A";

class EmulatedFalcon {
 public:
  void script(std::vector<Step> steps) {
    std::lock_guard lock(mutex_);
    steps_.assign(steps.begin(), steps.end());
  }
  std::size_t steps_left() {
    std::lock_guard lock(mutex_);
    return steps_.size();
  }
  std::string mismatch() {
    std::lock_guard lock(mutex_);
    return mismatch_;
  }

  // usbdevfs ioctls on the emulated node, from umockdev's thread.
  bool handle(UMockdevIoctlClient* client) {
    std::lock_guard lock(mutex_);
    const unsigned long request = umockdev_ioctl_client_get_request(client);
    UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
    switch (request) {
      case USBDEVFS_GET_CAPABILITIES: {
        UMockdevIoctlData* data = umockdev_ioctl_data_resolve(arg, 0, sizeof(guint32), nullptr);
        *reinterpret_cast<guint32*>(data->data) =
            USBDEVFS_CAP_BULK_CONTINUATION | USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
            USBDEVFS_CAP_REAP_AFTER_DISCONNECT | USBDEVFS_CAP_ZERO_PACKET;
        umockdev_ioctl_data_unref(data);
        umockdev_ioctl_client_complete(client, 0, 0);
        return true;
      }
      case USBDEVFS_GETDRIVER:  // no kernel driver on the interface
        umockdev_ioctl_client_complete(client, -1, ENODATA);
        return true;
      case USBDEVFS_CLAIMINTERFACE:
      case USBDEVFS_RELEASEINTERFACE:
      case USBDEVFS_CLEAR_HALT:
      case USBDEVFS_RESET:
      case USBDEVFS_RESETEP:
        umockdev_ioctl_client_complete(client, 0, 0);
        return true;
      case USBDEVFS_SUBMITURB:
        return submit(client, arg);
      case USBDEVFS_REAPURB:
      case USBDEVFS_REAPURBNDELAY:
        return reap(client, arg);
      case USBDEVFS_DISCARDURB:
        umockdev_ioctl_client_complete(client, -1, EINVAL);
        return true;
      default:
        return false;
    }
  }

 private:
  struct Flying {
    UMockdevIoctlData* urb;
    Bytes answer;  // control: setup and data; bulk IN: the data; bulk OUT: none
    int actual_length;
    int status;
  };

  bool submit(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
    UMockdevIoctlData* urb_data =
        umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_urb), nullptr);
    auto* urb = reinterpret_cast<usbdevfs_urb*>(urb_data->data);
    UMockdevIoctlData* buffer = umockdev_ioctl_data_resolve(
        urb_data, G_STRUCT_OFFSET(usbdevfs_urb, buffer), urb->buffer_length, nullptr);
    const auto* data = reinterpret_cast<const std::uint8_t*>(buffer->data);
    const bool is_in = (urb->endpoint & 0x80) != 0;
    const std::size_t shown = is_in && urb->type != USBDEVFS_URB_TYPE_CONTROL
                                  ? 0
                                  : std::min<std::size_t>(urb->buffer_length, 62);

    // Standard requests (string descriptors for the serial) are answered whenever asked.
    if (urb->type == USBDEVFS_URB_TYPE_CONTROL && data[0] == 0x80 && data[1] == 6) {
      Bytes answer(data, data + 8);
      const Bytes descriptor = string_descriptor(data[2]);
      const std::size_t room = static_cast<std::size_t>(urb->buffer_length) - 8;
      answer.insert(answer.end(), descriptor.begin(),
                    descriptor.begin() + std::min(room, descriptor.size()));
      flying_.push_back({urb_data, answer, static_cast<int>(answer.size()) - 8, 0});
      umockdev_ioctl_data_unref(buffer);
      umockdev_ioctl_client_complete(client, 0, 0);
      return true;
    }

    const char* problem = nullptr;
    if (steps_.empty()) {
      problem = "no URB was expected";
    } else {
      const Step& step = steps_.front();
      if (step.type != urb->type || step.endpoint != urb->endpoint) {
        problem = "wrong transfer type or endpoint";
      } else if (!is_in || urb->type == USBDEVFS_URB_TYPE_CONTROL) {
        if (static_cast<std::size_t>(urb->buffer_length) != step.sent.size() ||
            std::memcmp(data, step.sent.data(), step.sent.size()) != 0) {
          problem = "wrong bytes";
        }
      } else if (static_cast<std::size_t>(urb->buffer_length) < step.answer.size()) {
        problem = "IN buffer too small";
      }
    }
    if (problem != nullptr) {
      if (mismatch_.empty()) {
        mismatch_ = std::string(problem) + ": got type " + std::to_string(urb->type) +
                    " endpoint " + std::to_string(urb->endpoint) + " length " +
                    std::to_string(urb->buffer_length) + " [" + hex(data, shown) + "]";
        if (!steps_.empty()) {
          const Step& step = steps_.front();
          mismatch_ += ", expected type " + std::to_string(step.type) + " endpoint " +
                       std::to_string(step.endpoint) + " [" +
                       hex(step.sent.data(), step.sent.size()) + "]";
        }
      }
      umockdev_ioctl_data_unref(buffer);
      umockdev_ioctl_data_unref(urb_data);
      umockdev_ioctl_client_complete(client, -1, EPIPE);
      return true;
    }
    const Step step = steps_.front();
    steps_.pop_front();
    umockdev_ioctl_data_unref(buffer);
    if (step.submit_errno != 0) {
      umockdev_ioctl_data_unref(urb_data);
      umockdev_ioctl_client_complete(client, -1, step.submit_errno);
      return true;
    }
    if (urb->type == USBDEVFS_URB_TYPE_CONTROL) {
      flying_.push_back({urb_data, step.sent, 0, step.reap_status});
    } else if (is_in) {
      flying_.push_back(
          {urb_data, step.answer, static_cast<int>(step.answer.size()), step.reap_status});
    } else {
      flying_.push_back({urb_data, {}, urb->buffer_length, step.reap_status});  // all written
    }
    umockdev_ioctl_client_complete(client, 0, 0);
    return true;
  }

  bool reap(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
    if (flying_.empty()) {
      umockdev_ioctl_client_complete(client, -1, EAGAIN);
      return true;
    }
    Flying done = flying_.front();
    flying_.pop_front();
    auto* urb = reinterpret_cast<usbdevfs_urb*>(done.urb->data);
    // The handler shares the client's address space: write the answer in place.
    if (!done.answer.empty()) std::memcpy(urb->buffer, done.answer.data(), done.answer.size());
    urb->actual_length = done.actual_length;
    urb->status = done.status;
    UMockdevIoctlData* pointer = umockdev_ioctl_data_resolve(arg, 0, sizeof(gpointer), nullptr);
    umockdev_ioctl_data_set_ptr(pointer, 0, done.urb);
    umockdev_ioctl_data_unref(pointer);
    umockdev_ioctl_data_unref(done.urb);
    umockdev_ioctl_client_complete(client, 0, 0);
    return true;
  }

  static Bytes string_descriptor(std::uint8_t index) {
    if (index == 0) return {4, 3, 0x09, 0x04};  // English (US)
    const std::string text = index == 3 ? kSerial : "Novint Falcon";
    Bytes out{static_cast<std::uint8_t>(2 + 2 * text.size()), 3};
    for (char c : text) {
      out.push_back(static_cast<std::uint8_t>(c));
      out.push_back(0);
    }
    return out;
  }

  std::mutex mutex_;
  std::deque<Step> steps_;
  std::deque<Flying> flying_;
  std::string mismatch_;
};

gboolean on_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer falcon) {
  return static_cast<EmulatedFalcon*>(falcon)->handle(client) ? TRUE : FALSE;
}

class FalconUsbTest : public ::testing::Test {
 protected:
  void SetUp() override {
    testbed_ = umockdev_testbed_new();
    ASSERT_TRUE(umockdev_in_mock_environment())
        << "run this test under umockdev-wrapper (ctest does): it needs umockdev's preload "
           "library to emulate the Falcon's USB node";
    handler_ = umockdev_ioctl_base_new();
    g_signal_connect(handler_, "handle-ioctl", G_CALLBACK(on_ioctl), &falcon_);
    GError* error = nullptr;
    ASSERT_TRUE(umockdev_testbed_attach_ioctl(testbed_, "/dev/bus/usb/001/001", handler_, &error))
        << (error != nullptr ? error->message : "");
    ASSERT_TRUE(umockdev_testbed_add_from_string(testbed_, kFalconSysfs, &error))
        << (error != nullptr ? error->message : "");
  }

  void TearDown() override {
    g_clear_object(&handler_);
    g_clear_object(&testbed_);
  }

  // The FTDI's runtime mode: latency 1 ms, the fast baud rate, both buffers purged.
  static void append_normal_mode(std::vector<Step>& steps) {
    for (const Step& step : {ftdi(9, 1), ftdi(3, 0x2), ftdi(0, 1), ftdi(0, 2)}) {
      steps.push_back(step);
    }
  }
  // open(): purge, runtime mode; then (after any firmware) one exchange that the
  // firmware answers, in two IN reads.
  static std::vector<Step> opening() {
    std::vector<Step> steps{ftdi(0, 1), ftdi(0, 2)};
    append_normal_mode(steps);
    return steps;
  }
  static void append_firmware_check(std::vector<Step>& steps) {
    const Bytes reply = bytes(encode_reply({{-516, -516, -516}, 0, 0}));
    steps.push_back(out(bytes(encode(Command{}))));
    steps.push_back(in(Bytes(reply.begin(), reply.begin() + 10)));
    steps.push_back(in(Bytes(reply.begin() + 10, reply.end())));
  }

  void expect_script_done() {
    EXPECT_EQ(falcon_.mismatch(), "");
    EXPECT_EQ(falcon_.steps_left(), 0U) << "the driver stopped before the script's end";
  }

  EmulatedFalcon falcon_;
  UMockdevTestbed* testbed_{nullptr};
  UMockdevIoctlBase* handler_{nullptr};
};

// A firmware-sized image that is not Novint's: the driver only streams and compares it.
Bytes fake_firmware(std::size_t size) {
  Bytes image(size);
  std::uint32_t state = 15;
  for (auto& byte : image) {
    state = state * 1664525U + 1013904223U;
    byte = static_cast<std::uint8_t>(state >> 24);
  }
  return image;
}

std::string write_temporary(const Bytes& content, const char* name) {
  const auto path = std::filesystem::temp_directory_path() / name;
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(content.data()),
             static_cast<std::streamsize>(content.size()));
  return path.string();
}

TEST_F(FalconUsbTest, UploadsTheFirmwareThenExchangesPackets) {
  const Bytes image = fake_firmware(1100);  // 17 chunks of 62 bytes, then 46
  std::vector<Step> steps = opening();
  // The firmware upload: 9600 baud 8N1, RTS low, DTR low then high.
  for (const Step& step : {ftdi(0, 1), ftdi(0, 2), ftdi(9, 16), ftdi(3, 0x4138), ftdi(4, 8),
                           ftdi(2, 0), ftdi(1, 0x0200), ftdi(1, 0x0100), ftdi(1, 0x0101)}) {
    steps.push_back(step);
  }
  // The bootloader handshake: the first probe gets nothing, the second its answer.
  steps.push_back(out({0x0a, 0x43, 0x0d}));
  steps.push_back(in({}));
  steps.push_back(out({0x0a, 0x43, 0x0d}));
  steps.push_back(in({0x0a, 0x44, 0x2c, 0x0d}));
  steps.push_back(ftdi(1, 0x0100));
  steps.push_back(ftdi(3, 0x15));
  steps.push_back(out({'A'}));
  steps.push_back(in({'A'}));
  // The image in 62-byte chunks, each echoed back; chunk 3's echo comes in two reads.
  for (std::size_t offset = 0, chunk = 0; offset < image.size(); offset += 62, ++chunk) {
    const Bytes piece(image.begin() + static_cast<long>(offset),
                      image.begin() + static_cast<long>(std::min(offset + 62, image.size())));
    steps.push_back(out(piece));
    if (chunk == 3) {
      steps.push_back(in(Bytes(piece.begin(), piece.begin() + 20)));
      steps.push_back(in(Bytes(piece.begin() + 20, piece.end())));
    } else {
      steps.push_back(in(piece));
    }
  }
  append_normal_mode(steps);
  append_firmware_check(steps);
  // One packet exchange at 1 kHz: motors and LEDs out, encoders and buttons back.
  const Command command{{1200, -3400, 32767}, kLedGreen, false};
  const Reply reply{{-500, 250, 1000}, 0b0101, 0b111};
  steps.push_back(out(bytes(encode(command))));
  steps.push_back(in(bytes(encode_reply(reply))));
  falcon_.script(steps);

  UsbOptions options;
  options.firmware_path = write_temporary(image, "afhub_falcon_usb_test_firmware.bin");
  std::unique_ptr<FalconUsb> usb;
  ASSERT_NO_THROW(usb = FalconUsb::open(options)) << falcon_.mismatch();
  EXPECT_EQ(usb->serial(), kSerial);
  const TransportReply got = usb->exchange(encode(command));
  ASSERT_TRUE(got.received);
  const DecodedReply decoded = decode_reply(got.packet);
  ASSERT_TRUE(decoded.ok()) << describe(decoded.fault);
  EXPECT_EQ(decoded.reply.encoders, reply.encoders);
  EXPECT_EQ(decoded.reply.grip_buttons, reply.grip_buttons);
  EXPECT_EQ(decoded.reply.homed, reply.homed);
  expect_script_done();
}

TEST_F(FalconUsbTest, AFirmwareEchoThatDiffersIsRefused) {
  const Bytes image = fake_firmware(1024);
  std::vector<Step> steps = opening();
  for (const Step& step : {ftdi(0, 1), ftdi(0, 2), ftdi(9, 16), ftdi(3, 0x4138), ftdi(4, 8),
                           ftdi(2, 0), ftdi(1, 0x0200), ftdi(1, 0x0100), ftdi(1, 0x0101)}) {
    steps.push_back(step);
  }
  steps.push_back(out({0x0a, 0x43, 0x0d}));
  steps.push_back(in({0x0a, 0x44, 0x2c, 0x0d}));
  steps.push_back(ftdi(1, 0x0100));
  steps.push_back(ftdi(3, 0x15));
  steps.push_back(out({'A'}));
  steps.push_back(in({'A'}));
  Bytes first(image.begin(), image.begin() + 62);
  steps.push_back(out(first));
  first[5] ^= 0xff;  // the device echoes byte 5 wrong
  steps.push_back(in(first));
  falcon_.script(steps);

  UsbOptions options;
  options.firmware_path = write_temporary(image, "afhub_falcon_usb_test_bad_echo.bin");
  try {
    FalconUsb::open(options);
    FAIL() << "a corrupt upload was accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("firmware byte 5 echoed as"), std::string::npos)
        << error.what();
  }
  expect_script_done();
}

TEST_F(FalconUsbTest, UnpluggingIsDeviceGone) {
  std::vector<Step> steps = opening();
  append_firmware_check(steps);
  // The next packet's submit finds the device gone.
  Step unplugged = out(bytes(encode(Command{})));
  unplugged.submit_errno = ENODEV;
  steps.push_back(unplugged);
  falcon_.script(steps);

  std::unique_ptr<FalconUsb> usb;
  ASSERT_NO_THROW(usb = FalconUsb::open(UsbOptions{})) << falcon_.mismatch();
  try {
    usb->exchange(encode(Command{}));
    FAIL() << "an unplugged Falcon was not reported";
  } catch (const DeviceGone& gone) {
    EXPECT_NE(std::string(gone.what()).find("LIBUSB_ERROR_NO_DEVICE"), std::string::npos)
        << gone.what();
    EXPECT_NE(std::string(gone.what()).find("unplugged"), std::string::npos) << gone.what();
  }
  expect_script_done();
}

TEST_F(FalconUsbTest, ABusErrorDuringAnExchangeIsDeviceGoneForTheDevice) {
  std::vector<Step> steps = opening();
  append_firmware_check(steps);
  // A packet goes out, then its read fails on the bus (-EPROTO: LIBUSB_ERROR_IO).
  steps.push_back(out(bytes(encode(Command{{0, 0, 0}, kLedGreen, false}))));
  Step broken = in({});
  broken.reap_status = -EPROTO;
  steps.push_back(broken);
  falcon_.script(steps);

  std::unique_ptr<FalconDevice> device;
  ASSERT_NO_THROW(device = FalconDevice::open_usb(UsbOptions{})) << falcon_.mismatch();
  EXPECT_STREQ(device->spec().serial.data(), kSerial);
  EXPECT_THROW(device->exchange(DeviceOutput{}), DeviceGone);
  expect_script_done();
}

TEST_F(FalconUsbTest, AnotherSerialIsNotOpened) {
  UsbOptions options;
  options.serial = "NOT-THIS-ONE";
  try {
    FalconUsb::open(options);
    FAIL() << "a Falcon with another serial was opened";
  } catch (const std::runtime_error& error) {
    const std::string text = error.what();
    EXPECT_NE(text.find("with serial 'NOT-THIS-ONE'"), std::string::npos) << text;
    EXPECT_NE(text.find(std::string("Falcons present: ") + kSerial), std::string::npos) << text;
  }
  expect_script_done();
}

TEST(FalconFirmwareFile, BadFilesAreClearErrorsNamingThePath) {
  const auto expect_error = [](const std::string& path, const char* says) {
    try {
      read_firmware(path);
      FAIL() << path << " was accepted";
    } catch (const std::runtime_error& error) {
      const std::string text = error.what();
      EXPECT_NE(text.find(path), std::string::npos) << text;
      EXPECT_NE(text.find(says), std::string::npos) << text;
    }
  };
  expect_error("/nonexistent/falcon_firmware.bin", "cannot be read");
  expect_error(write_temporary(Bytes(10, 0x55), "afhub_falcon_short.bin"), "has 10 bytes");
  expect_error(write_temporary(Bytes(kMaxFirmwareBytes + 1, 0x55), "afhub_falcon_long.bin"),
               "bytes; a firmware image has");
  expect_error(std::filesystem::temp_directory_path().string(), "is a directory");
  EXPECT_EQ(read_firmware(write_temporary(fake_firmware(2000), "afhub_falcon_ok.bin")).size(),
            2000U);
}

}  // namespace
}  // namespace afhub::devices::falcon
