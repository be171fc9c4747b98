// A device's force gate by name, as `afhub echo` and the Python module show it.
#pragma once

#include "afhub/shm_layout/device.hpp"

namespace afhub {

constexpr const char* force_gate_name(ForceGate gate) {
  switch (gate) {
    case ForceGate::kApplying:
      return "applying";
    case ForceGate::kDisabled:
      return "disabled";
    case ForceGate::kNoCommand:
      return "no command";
    case ForceGate::kWatchdog:
      return "watchdog";
    case ForceGate::kStopping:
      return "stopping";
  }
  return "unknown";  // a value from a newer or corrupt writer
}

}  // namespace afhub
