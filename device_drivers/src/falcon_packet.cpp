#include "afhub/devices/falcon_packet.hpp"

#include <cstdio>

namespace afhub::devices::falcon {
namespace {

constexpr std::uint8_t kStart = '<';
constexpr std::uint8_t kEnd = '>';
constexpr std::uint8_t kZero = 0x41;  // payload bytes are kZero + a value
constexpr std::size_t kStatusByte = 13;

void put_int16(Packet& packet, std::size_t first, std::int16_t value) {
  const auto bits = static_cast<std::uint16_t>(value);
  for (std::size_t nibble = 0; nibble < 4; ++nibble) {
    packet[first + nibble] = static_cast<std::uint8_t>(kZero + ((bits >> (4 * nibble)) & 0xF));
  }
}

// Reads the three int16 values of bytes 1..12; false (and `fault`) on a bad byte.
bool get_int16s(const Packet& packet, std::array<std::int16_t, 3>& values, PacketFault& fault) {
  for (std::size_t leg = 0; leg < 3; ++leg) {
    std::uint16_t bits = 0;
    for (std::size_t nibble = 0; nibble < 4; ++nibble) {
      const std::size_t at = 1 + 4 * leg + nibble;
      const std::uint8_t byte = packet[at];
      if (byte < kZero || byte > kZero + 0xF) {
        fault = {PacketError::kBadNibble, at, byte};
        return false;
      }
      bits = static_cast<std::uint16_t>(bits | ((byte - kZero) << (4 * nibble)));
    }
    values[leg] = static_cast<std::int16_t>(bits);
  }
  return true;
}

bool check_framing(const Packet& packet, PacketFault& fault) {
  if (packet[0] != kStart) {
    fault = {PacketError::kBadStart, 0, packet[0]};
    return false;
  }
  if (packet[kPacketSize - 1] != kEnd) {
    fault = {PacketError::kBadEnd, kPacketSize - 1, packet[kPacketSize - 1]};
    return false;
  }
  return true;
}

}  // namespace

Packet encode(const Command& command) {
  Packet packet{};
  packet.fill(kZero);
  packet[0] = kStart;
  packet[kPacketSize - 1] = kEnd;
  for (std::size_t leg = 0; leg < 3; ++leg) put_int16(packet, 1 + 4 * leg, command.motors[leg]);
  const auto status =
      static_cast<std::uint8_t>((command.leds & kAllLeds) | (command.homing ? 1 : 0));
  packet[kStatusByte] = static_cast<std::uint8_t>(kZero + status);
  return packet;
}

Packet encode_reply(const Reply& reply) {
  Packet packet{};
  packet.fill(kZero);
  packet[0] = kStart;
  packet[kPacketSize - 1] = kEnd;
  for (std::size_t leg = 0; leg < 3; ++leg) put_int16(packet, 1 + 4 * leg, reply.encoders[leg]);
  const auto status =
      static_cast<std::uint8_t>(((reply.homed & kAllHomed) << 4) | (reply.grip_buttons & 0xF));
  packet[kStatusByte] = static_cast<std::uint8_t>(kZero + status);
  return packet;
}

DecodedReply decode_reply(const Packet& packet) {
  DecodedReply out;
  if (!check_framing(packet, out.fault)) return out;
  if (!get_int16s(packet, out.reply.encoders, out.fault)) return out;
  // Byte 13: 0x41 + (homed bits << 4 | grip nibble), seven bits in all. Byte 14 carries
  // nothing known (libnifalcon ignores it), so it is not checked.
  const std::uint8_t status = packet[kStatusByte];
  if (status < kZero || status - kZero > 0x7F) {
    out.fault = {PacketError::kBadStatus, kStatusByte, status};
    return out;
  }
  out.reply.grip_buttons = static_cast<std::uint8_t>((status - kZero) & 0xF);
  out.reply.homed = static_cast<std::uint8_t>(((status - kZero) >> 4) & kAllHomed);
  return out;
}

DecodedCommand decode_command(const Packet& packet) {
  DecodedCommand out;
  if (!check_framing(packet, out.fault)) return out;
  if (!get_int16s(packet, out.command.motors, out.fault)) return out;
  const std::uint8_t status = packet[kStatusByte];
  if (status < kZero || status > kZero + 0xF) {
    out.fault = {PacketError::kBadStatus, kStatusByte, status};
    return out;
  }
  out.command.leds = static_cast<std::uint8_t>((status - kZero) & kAllLeds);
  out.command.homing = ((status - kZero) & 1) != 0;
  return out;
}

std::string describe(const PacketFault& fault) {
  char text[128];
  switch (fault.error) {
    case PacketError::kNone:
      return "well formed";
    case PacketError::kBadStart:
      std::snprintf(text, sizeof text, "byte 0 is 0x%02x, not '<' (0x3c): out of step",
                    fault.value);
      break;
    case PacketError::kBadEnd:
      std::snprintf(text, sizeof text, "byte 15 is 0x%02x, not '>' (0x3e): out of step",
                    fault.value);
      break;
    case PacketError::kBadNibble:
      std::snprintf(text, sizeof text, "byte %zu is 0x%02x, not 0x41 + a nibble (0x41..0x50)",
                    fault.byte, fault.value);
      break;
    case PacketError::kBadStatus:
      std::snprintf(text, sizeof text, "byte %zu (buttons and homing) is 0x%02x, out of range",
                    fault.byte, fault.value);
      break;
  }
  return text;
}

std::string hex(const Packet& packet) {
  std::string out;
  char byte[4];
  for (std::size_t i = 0; i < packet.size(); ++i) {
    std::snprintf(byte, sizeof byte, i == 0 ? "%02x" : " %02x", packet[i]);
    out += byte;
  }
  return out;
}

}  // namespace afhub::devices::falcon
