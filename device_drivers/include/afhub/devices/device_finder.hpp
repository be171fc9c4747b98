// The supported devices plugged in: Novint Falcons on USB, and SpaceMice and
// gamepads among the evdev input devices, each with why it cannot be opened, if so.
#pragma once

#include <string>
#include <vector>

namespace afhub::devices {

struct FoundDevice {
  std::string kind;     // "falcon", "spacemouse" or "gamepad"
  std::string path;     // /dev/bus/usb/BBB/DDD or /dev/input/eventN
  std::string name;     // the device's own name
  std::string serial;   // empty when unknown
  std::string problem;  // empty when this user can open it; else what to do
};

struct DeviceScan {
  std::vector<FoundDevice> devices;  // USB first, then evdev by path
  std::vector<std::string> notes;    // a bus that could not be scanned, and why
};

DeviceScan find_devices();

// A SpaceMouse by its USB ids: 3Dconnexion's under Logitech (046d:c603..c640) and
// under its own vendor id (256f:c62e..c652).
bool is_spacemouse(unsigned vendor, unsigned product);

// One line per device, then the notes; says so when there is none.
std::string render_devices_text(const DeviceScan& scan);
// {"devices": [{"kind", "path", "name", "serial", "problem"}...], "notes": [...]}
std::string render_devices_json(const DeviceScan& scan);

}  // namespace afhub::devices
