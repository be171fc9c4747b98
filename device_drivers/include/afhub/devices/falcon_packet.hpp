// The Novint Falcon's 16-byte runtime packets (the firmware libnifalcon calls "Novint
// SDK"): '<', 14 printable payload bytes, '>'. A payload byte is 0x41 plus a nibble;
// each of the three int16 values takes bytes 1..12, four nibbles each, least
// significant first. Pure functions: no I/O, no allocation (describe() aside).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace afhub::devices::falcon {

inline constexpr std::size_t kPacketSize = 16;
using Packet = std::array<std::uint8_t, kPacketSize>;

// Byte 13 of a command: LED bits, and bit 0 asks the firmware to home the legs.
enum Led : std::uint8_t {
  kLedGreen = 0x2,
  kLedBlue = 0x4,
  kLedRed = 0x8,
};
inline constexpr std::uint8_t kAllLeds = kLedGreen | kLedBlue | kLedRed;
inline constexpr std::uint8_t kAllHomed = 0x7;

// Host -> device.
struct Command {
  std::array<std::int16_t, 3> motors{};  // motor effort per leg
  std::uint8_t leds{0};                  // Led bits; others are ignored
  bool homing{false};
};

// Device -> host.
struct Reply {
  std::array<std::int16_t, 3> encoders{};  // encoder counts per leg
  std::uint8_t grip_buttons{0};            // bit i: grip button i pressed
  std::uint8_t homed{0};                   // bit i: leg i is homed
};

enum class PacketError : std::uint8_t {
  kNone = 0,
  kBadStart,   // byte 0 is not '<'
  kBadEnd,     // byte 15 is not '>'
  kBadNibble,  // a value byte is not 0x41 + a nibble
  kBadStatus,  // byte 13 is out of range
};

// What is wrong with a packet, and where.
struct PacketFault {
  PacketError error{PacketError::kNone};
  std::size_t byte{0};
  std::uint8_t value{0};
};

struct DecodedReply {
  Reply reply;
  PacketFault fault;
  bool ok() const { return fault.error == PacketError::kNone; }
};

struct DecodedCommand {
  Command command;
  PacketFault fault;
  bool ok() const { return fault.error == PacketError::kNone; }
};

Packet encode(const Command& command);
// What the firmware sends: for tests and emulated devices.
Packet encode_reply(const Reply& reply);
// Never throw: a malformed packet says which byte is wrong.
DecodedReply decode_reply(const Packet& packet);
DecodedCommand decode_command(const Packet& packet);

// "byte 5 is 0x3a, not 0x41 + a nibble (0x41..0x50)", for error messages.
std::string describe(const PacketFault& fault);
// The packet as hex, "3c 50 ... 3e".
std::string hex(const Packet& packet);

}  // namespace afhub::devices::falcon
