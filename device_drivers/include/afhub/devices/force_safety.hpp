// The force rules every driver enforces, whatever its clients send: no fresh
// command within the watchdog's timeout gives zero force; the force, torque and
// gripper force are clamped to the device's maxima (scaled, so a clamped force
// keeps its direction); force ramps in over ramp_s once enabled, and again after
// every interruption, the driver's own included (stopped or stalled between two cycles
// for longer than the watchdog). Pure: the driver loop feeds it the newest command each
// cycle.
#pragma once

#include <cstdint>

#include "afhub/devices/device.hpp"

namespace afhub::devices {

struct SafetyLimits {
  std::int64_t watchdog_ns = 10'000'000;  // no command this long: the force is zero by then
  double ramp_s = 0.2;                    // from zero to full force once enabled
  // The driver's period: a command that will be past the watchdog before the next
  // cycle is already stale, so the force is zero within watchdog_ns, not a cycle later.
  std::int64_t cycle_ns = 0;
};

class ForceSafety {
 public:
  ForceSafety(const DeviceSpec& spec, const SafetyLimits& limits);

  // The output for this cycle from the newest command (nullptr: none yet), at now_ns
  // (CLOCK_MONOTONIC, the clock of the command's publish stamp). `gate` says why the
  // force is zero, when it is.
  DeviceOutput apply(const DeviceCommand* command, std::int64_t now_ns, ForceGate& gate) noexcept;

  // The loop is stopping (a signal, the hub gone): zero from now on.
  void stop() noexcept { stopped_ = true; }

 private:
  DeviceSpec spec_;
  SafetyLimits limits_;
  std::int64_t applying_since_ns_ = -1;  // -1: not applying; the ramp starts over
  std::int64_t last_cycle_ns_ = -1;      // the previous apply()'s now_ns; -1: none
  bool stopped_ = false;
};

}  // namespace afhub::devices
