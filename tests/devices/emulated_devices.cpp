#include "emulated_devices.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <umockdev.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace afhub::test {
namespace {

constexpr int kKeyWords = KEY_CNT / 64;

input_absinfo axis(std::int32_t minimum, std::int32_t maximum, std::int32_t flat = 0) {
  input_absinfo info{};
  info.minimum = minimum;
  info.maximum = maximum;
  info.flat = flat;
  info.value = minimum < 0 ? 0 : minimum;
  return info;
}

// Sets bit `code` in an EVIOCGBIT-style byte bitmap of `size` bytes.
void set_bit(std::uint8_t* bits, std::size_t size, unsigned code) {
  if (code / 8 < size) bits[code / 8] |= static_cast<std::uint8_t>(1U << (code % 8));
}

// sysfs capabilities/key: 64-bit hex words, most significant first, leading
// zero words left out (as the kernel prints them).
std::string key_capabilities(const std::vector<std::uint16_t>& keys) {
  std::array<std::uint64_t, kKeyWords> words{};
  for (const auto code : keys) words[code / 64] |= std::uint64_t{1} << (code % 64);
  int top = kKeyWords - 1;
  while (top > 0 && words[top] == 0) --top;
  std::string out;
  for (int i = top; i >= 0; --i) {
    char word[20];
    std::snprintf(word, sizeof word, "%llx", static_cast<unsigned long long>(words[i]));
    out += word;
    if (i > 0) out += ' ';
  }
  return out;
}

// Answers one EVIOCG* ioctl from the description, as the kernel's evdev does:
// copies at most the caller's buffer size and returns the bytes copied.
gboolean handle_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer user_data) {
  auto* input = static_cast<EmulatedInput*>(user_data);
  const unsigned long request = umockdev_ioctl_client_get_request(client);
  if (_IOC_TYPE(request) != 'E') return FALSE;
  if (input->gone()) {
    umockdev_ioctl_client_complete(client, -1, ENODEV);
    return TRUE;
  }
  const InputDescription& d = input->description();
  const unsigned nr = _IOC_NR(request);
  const std::size_t size = _IOC_SIZE(request);
  std::vector<std::uint8_t> reply;
  bool known = true;
  if (nr == 0x01) {  // EVIOCGVERSION
    const int version = EV_VERSION;
    reply.assign(reinterpret_cast<const std::uint8_t*>(&version),
                 reinterpret_cast<const std::uint8_t*>(&version) + sizeof version);
  } else if (nr == 0x02) {  // EVIOCGID
    const input_id id{d.bustype, d.vendor, d.product, 0x0111};
    reply.assign(reinterpret_cast<const std::uint8_t*>(&id),
                 reinterpret_cast<const std::uint8_t*>(&id) + sizeof id);
  } else if (nr == 0x06 || nr == 0x08) {  // EVIOCGNAME, EVIOCGUNIQ
    const std::string& text = nr == 0x06 ? d.name : d.uniq;
    if (text.empty()) {
      umockdev_ioctl_client_complete(client, -1, ENOENT);
      return TRUE;
    }
    reply.assign(text.begin(), text.end());
    reply.push_back(0);
  } else if (nr == 0x07) {  // EVIOCGPHYS: none, as for a virtual device
    umockdev_ioctl_client_complete(client, -1, ENOENT);
    return TRUE;
  } else if (nr == 0x09 || (nr >= 0x18 && nr <= 0x1b)) {
    reply.assign(size, 0);  // no properties; no key, LED, sound or switch is on
  } else if (nr >= 0x20 && nr < 0x20 + EV_CNT) {  // EVIOCGBIT(type)
    reply.assign(size, 0);
    const unsigned type = nr - 0x20;
    if (type == 0) {
      set_bit(reply.data(), size, EV_SYN);
      if (!d.keys.empty()) set_bit(reply.data(), size, EV_KEY);
      if (!d.rels.empty()) set_bit(reply.data(), size, EV_REL);
      if (!d.abs.empty()) set_bit(reply.data(), size, EV_ABS);
    } else if (type == EV_KEY) {
      for (const auto code : d.keys) set_bit(reply.data(), size, code);
    } else if (type == EV_REL) {
      for (const auto code : d.rels) set_bit(reply.data(), size, code);
    } else if (type == EV_ABS) {
      for (const auto& [code, info] : d.abs) set_bit(reply.data(), size, code);
    }
  } else if (nr >= 0x40 && nr < 0x40 + ABS_CNT) {  // EVIOCGABS(code)
    const auto found = std::find_if(d.abs.begin(), d.abs.end(),
                                    [&](const auto& entry) { return entry.first == nr - 0x40; });
    if (found == d.abs.end()) {
      umockdev_ioctl_client_complete(client, -1, EINVAL);
      return TRUE;
    }
    reply.assign(reinterpret_cast<const std::uint8_t*>(&found->second),
                 reinterpret_cast<const std::uint8_t*>(&found->second) + sizeof(input_absinfo));
  } else {
    known = false;
  }
  if (!known) {
    umockdev_ioctl_client_complete(client, -1, EINVAL);
    return TRUE;
  }
  UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
  UMockdevIoctlData* buffer = umockdev_ioctl_data_resolve(arg, 0, size, nullptr);
  const std::size_t copied = std::min(size, reply.size());
  if (buffer != nullptr) std::memcpy(buffer->data, reply.data(), copied);
  // Fixed-size structures return 0; variable-length ones the bytes copied.
  const bool sized = nr == 0x06 || nr == 0x08 || nr == 0x09 || nr >= 0x18;
  const long result = sized && !(nr >= 0x40) ? static_cast<long>(copied) : 0;
  umockdev_ioctl_client_complete(client, result, 0);
  if (buffer != nullptr) g_object_unref(buffer);
  return TRUE;
}

// Reads go to the pty behind the node, until the device is gone.
gboolean handle_read(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer user_data) {
  if (!static_cast<EmulatedInput*>(user_data)->gone()) return FALSE;
  umockdev_ioctl_client_complete(client, -1, ENODEV);
  return TRUE;
}

}  // namespace

InputDescription spacemouse_compact() {
  InputDescription d;
  d.name = "3Dconnexion SpaceMouse Compact";
  d.uniq = "SMC-1234";
  d.vendor = 0x256f;
  d.product = 0xc635;
  d.keys = {BTN_0, BTN_1};
  for (std::uint16_t code = ABS_X; code <= ABS_RZ; ++code)
    d.abs.emplace_back(code, axis(-350, 350));
  return d;
}

InputDescription space_navigator_relative() {
  InputDescription d;
  d.name = "3Dconnexion SpaceNavigator";
  d.vendor = 0x046d;
  d.product = 0xc626;
  d.keys = {BTN_0, BTN_1};
  d.rels = {REL_X, REL_Y, REL_Z, REL_RX, REL_RY, REL_RZ};
  return d;
}

InputDescription gamepad() {
  InputDescription d;
  d.name = "Generic X-Box pad";
  d.uniq = "";
  d.vendor = 0x045e;
  d.product = 0x028e;
  d.keys = {BTN_SOUTH, BTN_EAST, BTN_NORTH, BTN_WEST, BTN_TL, BTN_TR, BTN_SELECT, BTN_START};
  d.abs = {{ABS_X, axis(-32768, 32767, 128)},
           {ABS_Y, axis(-32768, 32767, 128)},
           {ABS_Z, axis(0, 255)},
           {ABS_RX, axis(-32768, 32767, 128)},
           {ABS_RY, axis(-32768, 32767, 128)},
           {ABS_RZ, axis(0, 255)},
           {ABS_HAT0X, axis(-1, 1)},
           {ABS_HAT0Y, axis(-1, 1)}};
  return d;
}

InputDescription keyboard() {
  InputDescription d;
  d.name = "AT Translated Set 2 keyboard";
  d.bustype = BUS_I8042;
  d.vendor = 0x0001;
  d.product = 0x0001;
  d.keys = {KEY_ESC, KEY_1, KEY_A, KEY_ENTER};
  return d;
}

EmulatedInput::EmulatedInput(UMockdevTestbed* testbed, int number, InputDescription description)
    : testbed_(testbed), number_(number), description_(std::move(description)) {
  handler_ = umockdev_ioctl_base_new();
  g_signal_connect(handler_, "handle-ioctl", G_CALLBACK(handle_ioctl), this);
  g_signal_connect(handler_, "handle-read", G_CALLBACK(handle_read), this);
  GError* error = nullptr;
  if (!umockdev_testbed_attach_ioctl(testbed_, path().c_str(), handler_, &error)) {
    ADD_FAILURE() << "umockdev cannot attach to " << path() << ": " << error->message;
    g_error_free(error);
  }
  char ids[16];
  std::snprintf(ids, sizeof ids, "%04X:%04X", description_.vendor, description_.product);
  const std::string input = "/devices/pci0000:00/0000:00:14.0/usb1/1-" + std::to_string(number_) +
                            "/0003:" + ids + ".0001/input/input" + std::to_string(number_ + 10);
  sysfs_path_ = "/sys" + input + "/event" + std::to_string(number_);
  char id_text[64];
  std::snprintf(id_text, sizeof id_text, "A: id/vendor=%04x\nA: id/product=%04x\n",
                description_.vendor, description_.product);
  const std::string record = "P: " + input +
                             "\nE: SUBSYSTEM=input\n"
                             "A: name=" +
                             description_.name + "\nA: uniq=" + description_.uniq + "\n" + id_text +
                             "A: capabilities/key=" + key_capabilities(description_.keys) +
                             "\n\nP: " + input + "/event" + std::to_string(number_) +
                             "\nN: input/event" + std::to_string(number_) +
                             "\nE: SUBSYSTEM=input\nE: DEVNAME=" + path() + "\n";
  if (!umockdev_testbed_add_from_string(testbed_, record.c_str(), &error)) {
    ADD_FAILURE() << "umockdev cannot add " << path() << ": " << error->message;
    g_error_free(error);
  }
}

EmulatedInput::~EmulatedInput() {
  g_object_unref(handler_);
}

void EmulatedInput::send(std::uint16_t type, std::uint16_t code, std::int32_t value) {
  input_event event{};
  event.type = type;
  event.code = code;
  event.value = value;
  const int fd = umockdev_testbed_get_dev_fd(testbed_, path().c_str());
  ASSERT_GE(fd, 0) << "no pty behind " << path();
  ASSERT_EQ(write(fd, &event, sizeof event), static_cast<ssize_t>(sizeof event))
      << std::strerror(errno);
}

void EmulatedInput::unplug() {
  gone_ = true;
  umockdev_testbed_remove_device(testbed_, sysfs_path_.c_str());
}

Testbed::Testbed() : testbed_(umockdev_testbed_new()) {
  const char* preload = std::getenv("LD_PRELOAD");
  if (preload == nullptr || std::strstr(preload, "umockdev") == nullptr) {
    ADD_FAILURE() << "run this test under umockdev-wrapper (ctest does): without umockdev's "
                     "preload library the emulated devices are not seen";
  }
}

Testbed::~Testbed() {
  inputs_.clear();
  g_object_unref(testbed_);
}

EmulatedInput& Testbed::add_input(int number, InputDescription description) {
  inputs_.push_back(std::make_unique<EmulatedInput>(testbed_, number, std::move(description)));
  nodes_.push_back(inputs_.back()->path());
  return *inputs_.back();
}

void Testbed::add_falcon(int bus, int address) {
  char node[64];
  std::snprintf(node, sizeof node, "bus/usb/%03d/%03d", bus, address);
  // Device descriptor (0403:cb48, no serial string), one configuration with one
  // vendor interface and the Falcon's bulk endpoints 0x02 and 0x81.
  const std::string descriptors =
      "1201000200000008030448cb000601020001"  // device
      "090220000101008032"                    // configuration
      "0904000002ffffff02"                    // interface 0
      "07050202400000"                        // bulk OUT 0x02
      "07058102400000";                       // bulk IN 0x81
  const std::string record =
      "P: /devices/pci0000:00/0000:00:14.0/usb" + std::to_string(bus) + "/" + std::to_string(bus) +
      "-" + std::to_string(address) + "\nN: " + node +
      "\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\nE: DRIVER=usb\nE: BUSNUM=" +
      std::string(node + 8, 3) + "\nE: DEVNUM=" + std::string(node + 12, 3) + "\nE: DEVNAME=/dev/" +
      node + "\nA: busnum=" + std::to_string(bus) + "\\n\nA: devnum=" + std::to_string(address) +
      "\\n\nA: bConfigurationValue=1\\n\nA: speed=12\\n\nA: idVendor=0403\\n\n"
      "A: idProduct=cb48\\n\nA: product=FALCON HAPTIC\\n\nH: descriptors=" +
      descriptors + "\n";
  GError* error = nullptr;
  if (!umockdev_testbed_add_from_string(testbed_, record.c_str(), &error)) {
    ADD_FAILURE() << "umockdev cannot add the Falcon: " << error->message;
    g_error_free(error);
  }
  nodes_.push_back(std::string("/dev/") + node);
}

void Testbed::deny_nodes_to_users() {
  char* root_dir = umockdev_testbed_get_root_dir(testbed_);
  const std::string root = root_dir;
  g_free(root_dir);
  // Writable too: umockdev's uevent emulation (libusb's hotplug monitor) binds a
  // socket there for the process that listens.
  ASSERT_EQ(chmod(root.c_str(), 01777), 0) << root << ": " << std::strerror(errno);
  for (const std::string& node : nodes_) {
    // The node links to its pty: chmod follows the link.
    const std::string path = root + node;
    ASSERT_EQ(chmod(path.c_str(), 0600), 0) << path << ": " << std::strerror(errno);
    // umockdev's preload library connects to the node's ioctl socket before it opens
    // the node, and ends the process when it cannot: let everyone connect.
    chmod((root + "/ioctl" + node).c_str(), 0666);
  }
  chmod((root + "/ioctl/_default").c_str(), 0666);
}

}  // namespace afhub::test
