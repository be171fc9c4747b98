// A page's WebSocket frames, read with a cap (see page_socket.hpp).
#include "page_socket.hpp"

#include <poll.h>
#include <sys/socket.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "afhub/rt/clock.hpp"

namespace afhub::viewer {
namespace {

constexpr std::int64_t kPingAfterNs = 1'000'000'000;     // of silence
constexpr std::int64_t kSilenceLimitNs = 5'000'000'000;  // pings unanswered: gone
constexpr int kPollMs = 250;  // how soon a stop (keep_going false) is seen
constexpr std::size_t kMaxHeader = 14;

// A close frame's payload: the status code, big-endian, then the reason.
std::string close_payload(std::uint16_t status, std::string_view reason) {
  std::string payload{static_cast<char>(status >> 8), static_cast<char>(status & 0xFF)};
  payload.append(reason);
  return payload;
}

}  // namespace

PageEnd read_page_frames(int fd, const std::function<bool()>& keep_going, const SendFrame& send) {
  // Any frame that fits the cap fits here whole, so a full buffer always holds one.
  std::vector<std::uint8_t> buffer(kMaxHeader + kMaxPageFrame);
  std::size_t have = 0;
  std::int64_t last_heard_ns = monotonic_ns(), last_ping_ns = last_heard_ns;
  while (keep_going()) {
    pollfd wait{fd, POLLIN, 0};
    const int ready = poll(&wait, 1, kPollMs);
    const std::int64_t now = monotonic_ns();
    if (ready > 0) {
      const ssize_t got = recv(fd, buffer.data() + have, buffer.size() - have, 0);
      if (got <= 0) return {false, "the page closed its connection"};
      have += static_cast<std::size_t>(got);
    }
    while (const std::optional<FrameHeader> header = parse_frame_header(buffer.data(), have)) {
      if (header->length > kMaxPageFrame) {
        send(Opcode::kClose, close_payload(1009, "frame too large"));
        return {true, "a frame of " + std::to_string(header->length) +
                          " bytes came, more than the " + std::to_string(kMaxPageFrame) +
                          " a page may send"};
      }
      if (!header->masked) {
        send(Opcode::kClose, close_payload(1002, "unmasked frame"));
        return {true, "an unmasked frame came (a page masks every frame)"};
      }
      const std::size_t total = header->size + static_cast<std::size_t>(header->length);
      if (have < total) break;
      std::uint8_t* payload = buffer.data() + header->size;
      for (std::size_t i = 0; i < header->length; ++i) payload[i] ^= header->mask[i % 4];
      const std::string_view text(reinterpret_cast<const char*>(payload), header->length);
      if (header->opcode == static_cast<std::uint8_t>(Opcode::kPing)) {
        send(Opcode::kPong, text);
      } else if (header->opcode == static_cast<std::uint8_t>(Opcode::kClose)) {
        send(Opcode::kClose, text.substr(0, 2));
        return {false, "the page closed its WebSocket"};
      }  // pongs, and data the page has no reason to send, are read and dropped
      std::memmove(buffer.data(), buffer.data() + total, have - total);
      have -= total;
      last_heard_ns = now;
    }
    if (now - last_heard_ns > kSilenceLimitNs)
      return {false, "the page left 5 s of pings unanswered"};
    if (now - last_heard_ns > kPingAfterNs && now - last_ping_ns > kPingAfterNs) {
      send(Opcode::kPing, {});
      last_ping_ns = now;
    }
  }
  return {false, "the viewer stopped"};
}

}  // namespace afhub::viewer
