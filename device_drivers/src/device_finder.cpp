#include "afhub/devices/device_finder.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <libevdev/libevdev.h>
#include <libusb.h>
#include <linux/input.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace afhub::devices {
namespace {

constexpr unsigned kFalconVendor = 0x0403;
constexpr unsigned kFalconProduct = 0xcb48;
constexpr const char* kRulesHint = "install device_drivers/udev/60-afhub.rules, see README";

std::string permission_problem(const std::string& path) {
  return "permission denied on " + path + ": " + kRulesHint;
}

std::string open_problem(const std::string& path, const char* reason) {
  return std::string("cannot open ") + path + ": " + reason;
}

void scan_usb(DeviceScan& scan) {
  libusb_context* context = nullptr;
  if (const int rc = libusb_init(&context); rc != LIBUSB_SUCCESS) {
    scan.notes.push_back(std::string("USB not scanned: ") + libusb_strerror(rc));
    return;
  }
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(context, &list);
  if (count < 0) {
    scan.notes.push_back(std::string("USB not scanned: ") +
                         libusb_strerror(static_cast<int>(count)));
  }
  for (ssize_t i = 0; i < count; ++i) {
    libusb_device* device = list[i];
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(device, &descriptor) != LIBUSB_SUCCESS) continue;
    if (descriptor.idVendor != kFalconVendor || descriptor.idProduct != kFalconProduct) continue;
    char path[64];
    std::snprintf(path, sizeof path, "/dev/bus/usb/%03u/%03u", libusb_get_bus_number(device),
                  libusb_get_device_address(device));
    FoundDevice found{"falcon", path, "Novint Falcon", "", ""};
    libusb_device_handle* handle = nullptr;
    const int rc = libusb_open(device, &handle);
    if (rc == LIBUSB_SUCCESS) {
      unsigned char serial[128] = {};
      if (descriptor.iSerialNumber != 0 &&
          libusb_get_string_descriptor_ascii(handle, descriptor.iSerialNumber, serial,
                                             sizeof serial) > 0) {
        found.serial = reinterpret_cast<const char*>(serial);
      }
      libusb_close(handle);
    } else if (rc == LIBUSB_ERROR_ACCESS) {
      found.problem = permission_problem(path);
    } else {
      found.problem = open_problem(path, libusb_strerror(rc));
    }
    scan.devices.push_back(found);
  }
  if (count >= 0) libusb_free_device_list(list, 1);
  libusb_exit(context);
}

// What an input device is, from libevdev when it opens, else from sysfs (readable
// by everyone, so a device the user may not open is still named).
struct InputIdentity {
  std::string name;
  std::string serial;
  unsigned vendor{0};
  unsigned product{0};
  bool gamepad{false};  // has BTN_SOUTH (== BTN_GAMEPAD)
};

std::string read_line(const std::string& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  return line;
}

unsigned read_hex(const std::string& file) {
  return static_cast<unsigned>(std::strtoul(read_line(file).c_str(), nullptr, 16));
}

// sysfs capabilities: hex words, most significant first, each a long's bits.
bool capability_has(const std::string& words, unsigned bit) {
  std::istringstream in(words);
  std::vector<unsigned long> values;
  std::string word;
  while (in >> word) values.push_back(std::strtoul(word.c_str(), nullptr, 16));
  constexpr unsigned kBits = sizeof(unsigned long) * 8;
  const std::size_t index = bit / kBits;  // counted from the last word
  if (index >= values.size()) return false;
  return ((values[values.size() - 1 - index] >> (bit % kBits)) & 1UL) != 0;
}

InputIdentity identity_from_sysfs(const std::string& event_name) {
  // /sys/class/input/eventN is a link into the input device's directory.
  const std::string device = "/sys/class/input/" + event_name + "/../";
  InputIdentity id;
  id.name = read_line(device + "name");
  id.serial = read_line(device + "uniq");
  id.vendor = read_hex(device + "id/vendor");
  id.product = read_hex(device + "id/product");
  id.gamepad = capability_has(read_line(device + "capabilities/key"), BTN_SOUTH);
  return id;
}

bool identity_from_evdev(int fd, InputIdentity& id) {
  libevdev* dev = nullptr;
  if (libevdev_new_from_fd(fd, &dev) < 0) return false;
  const char* name = libevdev_get_name(dev);
  const char* uniq = libevdev_get_uniq(dev);
  id.name = name != nullptr ? name : "";
  id.serial = uniq != nullptr ? uniq : "";
  id.vendor = static_cast<unsigned>(libevdev_get_id_vendor(dev));
  id.product = static_cast<unsigned>(libevdev_get_id_product(dev));
  id.gamepad = libevdev_has_event_code(dev, EV_KEY, BTN_SOUTH) != 0;
  libevdev_free(dev);
  return true;
}

int event_number(const char* name) {
  if (std::strncmp(name, "event", 5) != 0 || name[5] == '\0') return -1;
  for (const char* c = name + 5; *c != '\0'; ++c) {
    if (*c < '0' || *c > '9') return -1;
  }
  return std::atoi(name + 5);
}

void scan_input(DeviceScan& scan) {
  DIR* dir = opendir("/dev/input");
  if (dir == nullptr) {
    if (errno != ENOENT) {
      scan.notes.push_back(std::string("input devices not scanned: /dev/input: ") +
                           std::strerror(errno));
    }
    return;
  }
  std::vector<int> numbers;
  while (const dirent* entry = readdir(dir)) {
    if (const int n = event_number(entry->d_name); n >= 0) numbers.push_back(n);
  }
  closedir(dir);
  std::sort(numbers.begin(), numbers.end());

  for (const int n : numbers) {
    const std::string event_name = "event" + std::to_string(n);
    const std::string path = "/dev/input/" + event_name;
    InputIdentity id;
    std::string problem;
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd >= 0) {
      const bool known = identity_from_evdev(fd, id);
      ::close(fd);
      if (!known) id = identity_from_sysfs(event_name);
    } else {
      const int error = errno;
      id = identity_from_sysfs(event_name);
      problem = error == EACCES || error == EPERM ? permission_problem(path)
                                                  : open_problem(path, std::strerror(error));
    }
    const char* kind = is_spacemouse(id.vendor, id.product) ? "spacemouse"
                       : id.gamepad                         ? "gamepad"
                                                            : nullptr;
    if (kind == nullptr) continue;
    scan.devices.push_back({kind, path, id.name, id.serial, problem});
  }
}

void append_json_string(std::string& out, const std::string& text) {
  out += '"';
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", static_cast<unsigned>(c));
      out += escaped;
    } else {
      out += c;
    }
  }
  out += '"';
}

}  // namespace

bool is_spacemouse(unsigned vendor, unsigned product) {
  return (vendor == 0x046d && product >= 0xc603 && product <= 0xc640) ||
         (vendor == 0x256f && product >= 0xc62e && product <= 0xc652);
}

DeviceScan find_devices() {
  DeviceScan scan;
  scan_usb(scan);
  scan_input(scan);
  return scan;
}

std::string render_devices_text(const DeviceScan& scan) {
  std::string out;
  if (scan.devices.empty()) out += "no supported device found (Falcon, SpaceMouse, gamepad)\n";
  for (const FoundDevice& device : scan.devices) {
    out += device.kind + "  " + device.path + "  " + device.name;
    if (!device.serial.empty()) out += "  serial " + device.serial;
    out += device.problem.empty() ? "  ok\n" : "\n  " + device.problem + "\n";
  }
  for (const std::string& note : scan.notes) out += "note: " + note + "\n";
  return out;
}

std::string render_devices_json(const DeviceScan& scan) {
  std::string out = "{\"devices\": [";
  for (std::size_t i = 0; i < scan.devices.size(); ++i) {
    const FoundDevice& device = scan.devices[i];
    out += i == 0 ? "{" : ", {";
    const std::pair<const char*, const std::string*> fields[] = {{"kind", &device.kind},
                                                                 {"path", &device.path},
                                                                 {"name", &device.name},
                                                                 {"serial", &device.serial},
                                                                 {"problem", &device.problem}};
    for (std::size_t f = 0; f < std::size(fields); ++f) {
      if (f > 0) out += ", ";
      out += std::string("\"") + fields[f].first + "\": ";
      append_json_string(out, *fields[f].second);
    }
    out += "}";
  }
  out += "], \"notes\": [";
  for (std::size_t i = 0; i < scan.notes.size(); ++i) {
    if (i > 0) out += ", ";
    append_json_string(out, scan.notes[i]);
  }
  out += "]}\n";
  return out;
}

}  // namespace afhub::devices
