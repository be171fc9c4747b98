// The WebSocket handshake key and frame headers (see websocket_frames.hpp).
#include "websocket_frames.hpp"

#include <array>
#include <cstring>

namespace afhub::viewer {
namespace {

std::uint32_t rotate_left(std::uint32_t value, int bits) {
  return (value << bits) | (value >> (32 - bits));
}

// SHA-1 (FIPS 180-4), for the handshake only: RFC 6455 names it; it protects nothing.
std::array<std::uint8_t, 20> sha1(std::string_view text) {
  std::uint32_t h[5] = {0x67452301, 0xEFCDAB89, 0x98BADCFE, 0x10325476, 0xC3D2E1F0};
  std::string message(text);
  const std::uint64_t bits = static_cast<std::uint64_t>(text.size()) * 8;
  message.push_back(static_cast<char>(0x80));
  while (message.size() % 64 != 56) message.push_back('\0');
  for (int shift = 56; shift >= 0; shift -= 8) message.push_back(static_cast<char>(bits >> shift));
  for (std::size_t block = 0; block < message.size(); block += 64) {
    std::uint32_t w[80];
    for (int i = 0; i < 16; ++i) {
      const auto* b = reinterpret_cast<const std::uint8_t*>(message.data() + block + 4 * i);
      w[i] = (std::uint32_t{b[0]} << 24) | (std::uint32_t{b[1]} << 16) |
             (std::uint32_t{b[2]} << 8) | b[3];
    }
    for (int i = 16; i < 80; ++i)
      w[i] = rotate_left(w[i - 3] ^ w[i - 8] ^ w[i - 14] ^ w[i - 16], 1);
    std::uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4];
    for (int i = 0; i < 80; ++i) {
      std::uint32_t f, k;
      if (i < 20) {
        f = (b & c) | (~b & d);
        k = 0x5A827999;
      } else if (i < 40) {
        f = b ^ c ^ d;
        k = 0x6ED9EBA1;
      } else if (i < 60) {
        f = (b & c) | (b & d) | (c & d);
        k = 0x8F1BBCDC;
      } else {
        f = b ^ c ^ d;
        k = 0xCA62C1D6;
      }
      const std::uint32_t next = rotate_left(a, 5) + f + e + k + w[i];
      e = d;
      d = c;
      c = rotate_left(b, 30);
      b = a;
      a = next;
    }
    h[0] += a;
    h[1] += b;
    h[2] += c;
    h[3] += d;
    h[4] += e;
  }
  std::array<std::uint8_t, 20> digest{};
  for (int i = 0; i < 20; ++i)
    digest[i] = static_cast<std::uint8_t>(h[i / 4] >> (24 - 8 * (i % 4)));
  return digest;
}

std::string base64(const std::uint8_t* data, std::size_t size) {
  static const char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string text;
  for (std::size_t i = 0; i < size; i += 3) {
    const std::uint32_t group = (std::uint32_t{data[i]} << 16) |
                                (i + 1 < size ? std::uint32_t{data[i + 1]} << 8 : 0) |
                                (i + 2 < size ? std::uint32_t{data[i + 2]} : 0);
    text.push_back(kDigits[(group >> 18) & 63]);
    text.push_back(kDigits[(group >> 12) & 63]);
    text.push_back(i + 1 < size ? kDigits[(group >> 6) & 63] : '=');
    text.push_back(i + 2 < size ? kDigits[group & 63] : '=');
  }
  return text;
}

}  // namespace

std::string websocket_accept(std::string_view key) {
  const std::array<std::uint8_t, 20> digest =
      sha1(std::string(key) + "258EAFA5-E914-47DA-95CA-C5AB0DC85B11");
  return base64(digest.data(), digest.size());
}

std::size_t write_frame_header(std::uint8_t (&out)[10], Opcode opcode, std::uint64_t length) {
  out[0] = static_cast<std::uint8_t>(0x80 | static_cast<std::uint8_t>(opcode));
  const std::size_t extended = length < 126 ? 0 : length < 65536 ? 2 : 8;
  out[1] = static_cast<std::uint8_t>(extended == 0 ? length : extended == 2 ? 126 : 127);
  for (std::size_t i = 0; i < extended; ++i)
    out[2 + i] = static_cast<std::uint8_t>(length >> (8 * (extended - 1 - i)));
  return 2 + extended;
}

std::optional<FrameHeader> parse_frame_header(const std::uint8_t* data, std::size_t available) {
  if (available < 2) return std::nullopt;
  FrameHeader header;
  header.fin = (data[0] & 0x80) != 0;
  header.opcode = data[0] & 0x0F;
  header.masked = (data[1] & 0x80) != 0;
  const std::uint8_t short_length = data[1] & 0x7F;
  const std::size_t extended = short_length == 126 ? 2 : short_length == 127 ? 8 : 0;
  header.size = 2 + extended + (header.masked ? 4 : 0);
  if (available < header.size) return std::nullopt;
  header.length = short_length;
  if (extended > 0) {
    header.length = 0;
    for (std::size_t i = 0; i < extended; ++i) header.length = (header.length << 8) | data[2 + i];
  }
  if (header.masked) std::memcpy(header.mask, data + 2 + extended, 4);
  return header;
}

}  // namespace afhub::viewer
