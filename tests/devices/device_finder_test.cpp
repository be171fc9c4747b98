// find_devices() on an emulated testbed (umockdev's sysfs and /dev): a Falcon on USB
// through the real libusb, a SpaceMouse and a gamepad among evdev nodes, a keyboard
// left out; then the same testbed seen by a user without permission.
#include "afhub/devices/device_finder.hpp"

#include <fcntl.h>
#include <grp.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>

#include "emulated_devices.hpp"

namespace afhub::devices {
namespace {

using test::Testbed;

void build_testbed(Testbed& testbed) {
  testbed.add_falcon(1, 4);
  testbed.add_input(2, test::keyboard());
  testbed.add_input(3, test::spacemouse_compact());
  testbed.add_input(11, test::gamepad());
  testbed.add_input(12, test::space_navigator_relative());
}

TEST(DeviceFinder, SpaceMouseIds) {
  EXPECT_TRUE(is_spacemouse(0x046d, 0xc626));
  EXPECT_TRUE(is_spacemouse(0x046d, 0xc603));
  EXPECT_TRUE(is_spacemouse(0x256f, 0xc652));
  EXPECT_FALSE(is_spacemouse(0x046d, 0xc52b));  // a Logitech receiver
  EXPECT_FALSE(is_spacemouse(0x256f, 0xc653));
}

TEST(DeviceFinder, ClassifiesTheEmulatedDevices) {
  Testbed testbed;
  build_testbed(testbed);
  const DeviceScan scan = find_devices();
  EXPECT_TRUE(scan.notes.empty()) << render_devices_text(scan);
  ASSERT_EQ(scan.devices.size(), 4U) << render_devices_text(scan);

  EXPECT_EQ(scan.devices[0].kind, "falcon");
  EXPECT_EQ(scan.devices[0].path, "/dev/bus/usb/001/004");
  EXPECT_EQ(scan.devices[0].problem, "");

  EXPECT_EQ(scan.devices[1].kind, "spacemouse");
  EXPECT_EQ(scan.devices[1].path, "/dev/input/event3");
  EXPECT_EQ(scan.devices[1].name, "3Dconnexion SpaceMouse Compact");
  EXPECT_EQ(scan.devices[1].serial, "SMC-1234");
  EXPECT_EQ(scan.devices[1].problem, "");

  EXPECT_EQ(scan.devices[2].kind, "gamepad");
  EXPECT_EQ(scan.devices[2].path, "/dev/input/event11");
  EXPECT_EQ(scan.devices[2].name, "Generic X-Box pad");

  EXPECT_EQ(scan.devices[3].kind, "spacemouse");
  EXPECT_EQ(scan.devices[3].path, "/dev/input/event12");

  const std::string text = render_devices_text(scan);
  EXPECT_NE(text.find("spacemouse  /dev/input/event3  3Dconnexion SpaceMouse Compact  serial "
                      "SMC-1234  ok\n"),
            std::string::npos)
      << text;
  const std::string json = render_devices_json(scan);
  EXPECT_NE(json.find("{\"kind\": \"falcon\", \"path\": \"/dev/bus/usb/001/004\", \"name\": "
                      "\"Novint Falcon\", \"serial\": \"\", \"problem\": \"\"}"),
            std::string::npos)
      << json;
}

TEST(DeviceFinder, NothingPlugged) {
  Testbed testbed;
  const DeviceScan scan = find_devices();
  EXPECT_TRUE(scan.devices.empty()) << render_devices_text(scan);
  EXPECT_NE(render_devices_text(scan).find("no supported device found"), std::string::npos);
  EXPECT_EQ(render_devices_json(scan).substr(0, 15), "{\"devices\": [],");
}

// As the user nobody, with the device nodes for root only (no udev rules), each
// device is still found and named, with the fix to apply.
TEST(DeviceFinder, ExplainsPermissionProblems) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root to become another user";
  Testbed testbed;
  build_testbed(testbed);
  testbed.deny_nodes_to_users();
  int out[2];
  ASSERT_EQ(pipe(out), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(out[0]);
    if (setgroups(0, nullptr) != 0 || setresgid(65534, 65534, 65534) != 0 ||
        setresuid(65534, 65534, 65534) != 0) {
      _exit(3);
    }
    const std::string text = render_devices_text(find_devices());
    if (write(out[1], text.data(), text.size()) != static_cast<ssize_t>(text.size())) _exit(4);
    _exit(0);
  }
  close(out[1]);
  std::string text;
  char buffer[512];
  for (ssize_t n; (n = read(out[0], buffer, sizeof buffer)) > 0;) text.append(buffer, n);
  close(out[0]);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;

  const std::string hint = ": install device_drivers/udev/60-afhub.rules, see README";
  for (const std::string path :
       {"/dev/bus/usb/001/004", "/dev/input/event3", "/dev/input/event11", "/dev/input/event12"}) {
    EXPECT_NE(text.find("permission denied on " + path + hint), std::string::npos)
        << path << " in\n"
        << text;
  }
  // Named from sysfs, which everyone may read.
  EXPECT_NE(text.find("spacemouse  /dev/input/event3  3Dconnexion SpaceMouse Compact  serial "
                      "SMC-1234\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("gamepad  /dev/input/event11  Generic X-Box pad\n"), std::string::npos)
      << text;
  EXPECT_EQ(text.find("keyboard"), std::string::npos) << text;
}

}  // namespace
}  // namespace afhub::devices
