// What FalconDevice needs from the wire: one 16-byte packet out, its 16-byte reply
// back. FalconUsb implements it over libusb; tests script it.
#pragma once

#include "afhub/devices/falcon_packet.hpp"

namespace afhub::devices::falcon {

struct TransportReply {
  Packet packet{};
  bool received{false};  // false: no complete reply in time (the device may be busy)
};

class FalconTransport {
 public:
  virtual ~FalconTransport() = default;
  // Sends `command` and waits for the reply. Throws DeviceGone when the device is lost
  // (unplugged, a USB error). Does not allocate itself.
  virtual TransportReply exchange(const Packet& command) = 0;
};

}  // namespace afhub::devices::falcon
