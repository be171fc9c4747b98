// The parts of the WebSocket protocol (RFC 6455) the viewer speaks itself: the
// handshake's accept key and the header of a frame from a page. Pure functions, so
// that they are tested without a socket.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace afhub::viewer {

// Sec-WebSocket-Accept for a request's Sec-WebSocket-Key: base64(SHA-1(key + GUID)).
std::string websocket_accept(std::string_view key);

// The opcodes a page may send.
enum class Opcode : std::uint8_t {
  kContinuation = 0x0,
  kText = 0x1,
  kBinary = 0x2,
  kClose = 0x8,
  kPing = 0x9,
  kPong = 0xA,
};

struct FrameHeader {
  bool fin = false;
  std::uint8_t opcode = 0;
  bool masked = false;
  std::uint64_t length = 0;  // of the payload, as the frame claims it
  std::size_t size = 0;      // of the header: 2 to 14 bytes
  std::uint8_t mask[4] = {};
};

// Writes the header of an unmasked frame (the server's: fin set) into `out`; returns
// its size, 2 to 10 bytes.
std::size_t write_frame_header(std::uint8_t (&out)[10], Opcode opcode, std::uint64_t length);

// The header at the start of `data`, or nothing while fewer bytes than it needs
// have come (read more, and ask again).
std::optional<FrameHeader> parse_frame_header(const std::uint8_t* data, std::size_t available);

}  // namespace afhub::viewer
