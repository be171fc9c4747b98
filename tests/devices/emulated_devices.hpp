// Input and USB devices emulated by umockdev, for the real libevdev and libusb code
// above them: this kernel has no uinput, so evdev nodes cannot be made for real.
//
// The test binary runs under umockdev-wrapper (umockdev's LD_PRELOAD library), which
// sends /dev and /sys into a testbed directory and every ioctl(), read() and write()
// on an emulated node to a handler in this process. An input device here answers
// libevdev's EVIOCG* ioctls from its description; its events go through the
// testbed's pty behind the node, written with send(); after unplug() every read
// and ioctl fails with ENODEV, as on a real evdev node whose device is gone.
#pragma once

#include <linux/input.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

typedef struct _UMockdevTestbed UMockdevTestbed;
typedef struct _UMockdevIoctlBase UMockdevIoctlBase;

namespace afhub::test {

struct InputDescription {
  std::string name;
  std::string uniq;
  std::uint16_t bustype{BUS_USB};
  std::uint16_t vendor{0};
  std::uint16_t product{0};
  std::vector<std::uint16_t> keys;  // EV_KEY codes
  std::vector<std::uint16_t> rels;  // EV_REL codes
  std::vector<std::pair<std::uint16_t, input_absinfo>> abs;
};

// A SpaceMouse with EV_ABS axes (-350..350) and two buttons (BTN_0, BTN_1).
InputDescription spacemouse_compact();
// A SpaceNavigator that reports EV_REL axes, as older kernels and models do.
InputDescription space_navigator_relative();
// A gamepad per the Linux gamepad specification.
InputDescription gamepad();
// A keyboard: neither a SpaceMouse nor a gamepad.
InputDescription keyboard();

class EmulatedInput {
 public:
  EmulatedInput(UMockdevTestbed* testbed, int number, InputDescription description);
  ~EmulatedInput();
  EmulatedInput(const EmulatedInput&) = delete;
  EmulatedInput& operator=(const EmulatedInput&) = delete;

  std::string path() const { return "/dev/input/event" + std::to_string(number_); }
  // Writes one event to the node, as the kernel queues it for readers.
  void send(std::uint16_t type, std::uint16_t code, std::int32_t value);
  void sync() { send(EV_SYN, SYN_REPORT, 0); }
  // The device goes away: reads and ioctls fail with ENODEV, sysfs forgets it.
  void unplug();

  const InputDescription& description() const { return description_; }
  bool gone() const { return gone_.load(); }

 private:
  UMockdevTestbed* testbed_;
  int number_;
  InputDescription description_;
  std::string sysfs_path_;
  UMockdevIoctlBase* handler_{nullptr};
  std::atomic<bool> gone_{false};
};

class Testbed {
 public:
  Testbed();  // fails the test unless running under umockdev-wrapper
  ~Testbed();
  Testbed(const Testbed&) = delete;
  Testbed& operator=(const Testbed&) = delete;

  EmulatedInput& add_input(int number, InputDescription description);
  // A Novint Falcon (0403:cb48) at /dev/bus/usb/BBB/DDD.
  void add_falcon(int bus, int address);
  // As on a machine without afhub's udev rules: the testbed directory open to
  // every user (umockdev makes it 0700), each device node (a pty umockdev makes
  // world-writable) for root only. For a test that becomes another user.
  void deny_nodes_to_users();

 private:
  UMockdevTestbed* testbed_;
  std::vector<std::unique_ptr<EmulatedInput>> inputs_;
  std::vector<std::string> nodes_;  // under /dev
};

}  // namespace afhub::test
