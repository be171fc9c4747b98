// A device driver process: the device's loop on the real-time loop runner (1 kHz by
// default), publishing DeviceState on {"afhub", "device/<name>", "state"} every cycle
// and applying the newest DeviceCommand from {"afhub", "device/<name>", "command"}
// under the force rules of force_safety.hpp. Force goes to zero, and the device is
// made safe, on Ctrl-C and SIGTERM, when the device goes away, and when the hub does
// (the driver then re-attaches to the next hub, as controllers do).
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "afhub/devices/device.hpp"
#include "afhub/devices/force_safety.hpp"
#include "afhub/rt/periodic_loop.hpp"

namespace afhub::devices {

struct DriverOptions {
  std::string name;  // the device's channel is device/<name>
  LoopOptions loop;  // 1 kHz; --fifo, --cpu, --lock-memory as for controllers
  SafetyLimits safety;
  double wait_s = 10.0;    // for the hub
  bool reconnect = false;  // when the device goes away, wait for it instead of exiting
  // Outlive the hub: make the device safe, re-execute and re-attach (hub_loss.hpp).
  // false: the process ends with its hub (a driver run inside a test binary).
  bool survive_hub_loss = true;
};

// Opens the device (throws afhub::Error, or DeviceGone when it is absent).
using DeviceOpener = std::function<std::unique_ptr<Device>()>;

// Runs the driver until a stop signal or options.loop.max_cycles. Returns 0 then; 1
// when the device went away (without options.reconnect).
int run_driver(const DeviceOpener& open, const DriverOptions& options);

}  // namespace afhub::devices
