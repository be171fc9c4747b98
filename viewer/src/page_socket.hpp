// A page's WebSocket (/ws), spoken by the viewer itself on the connection's socket.
// civetweb's own WebSocket reads a whole frame into memory, however long its header
// says it is, before anyone may look at it: three connections sending 1 GB frames
// took the viewer from 24 MB to 2.95 GB. Here a frame longer than a page ever sends
// is refused at its header, and the connection closed.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <string_view>

#include "websocket_frames.hpp"

namespace afhub::viewer {

// The longest frame a page may send. The page sends only control frames (a pong, a
// close), of at most 125 bytes each; a few KB would be plenty.
inline constexpr std::size_t kMaxPageFrame = 16 * 1024;

// Writes one unmasked frame to the page; returns whether it went out whole.
using SendFrame = std::function<bool(Opcode opcode, std::string_view payload)>;

struct PageEnd {
  bool refused = false;  // the page broke the rules (a frame too long or not masked)
  std::string why;
};

// Reads the page's frames from `fd` until the page closes, stays silent for 5 s
// (it is pinged after each second of silence), sends a frame longer than
// kMaxPageFrame or not masked (refused with a close frame), or `keep_going` turns
// false. Answers pings and a close. Says why it ended; the caller closes the
// connection.
PageEnd read_page_frames(int fd, const std::function<bool()>& keep_going, const SendFrame& send);

}  // namespace afhub::viewer
