// DeviceTape: each state a device's driver publishes, with the command it took that
// cycle when that was a new one, for a reader that must see every cycle (`afhub record
// --devices`), on {"afhub", "device/<name>", "tape"}. The state and command channels
// are latest-value slots: a reader that wakes late finds the newer update only. The tape
// keeps the last kDeviceTapeRingParts cycles instead, in a ring (tape_ring.hpp).
#pragma once

#include <cstdint>

#include "afhub/shm_layout/device.hpp"
#include "afhub/shm_layout/tape_ring.hpp"

namespace afhub {

struct DeviceTape {
  DeviceState state;
  DeviceCommand command;  // the command taken, when has_command is 1
  std::uint32_t has_command{0};
  std::uint32_t reserved{0};
};

// 400 ms of a 1 kHz driver: a reader survives a pause of that long (the step tape holds
// 320 ms of a small world). A ring takes 256 KB of the hub's pools while a recorder
// reads it (hub/daemon/src/hub_mempools.cpp).
inline constexpr std::uint32_t kDeviceTapeRingParts = 400;
inline constexpr std::uint64_t kDeviceTapeRingMagic = 0x61666875622d6474ULL;  // "afhub-dt"
using DeviceTapeRing = TapeRing<DeviceTape, kDeviceTapeRingParts, kDeviceTapeRingMagic>;

}  // namespace afhub
