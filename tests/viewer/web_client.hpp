// A minimal HTTP client on a raw socket (the request line is sent exactly as
// given, so "/mesh/../../etc/passwd" reaches the server unnormalised) and a
// WebSocket client (civetweb's) that counts the binary frames it receives.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

struct mg_connection;

namespace afhub::test {

struct HttpReply {
  int status = 0;  // 0: no answer
  std::string body;
};

// From `from` (a loopback address such as "127.0.0.2"; empty: the default, 127.0.0.1),
// with `headers` ("Name: value\r\n" each; they name the Host).
inline constexpr const char* kLoopbackHost = "Host: 127.0.0.1\r\n";
HttpReply http_request(int port, const std::string& method, const std::string& target,
                       const std::string& from = "", const std::string& headers = kLoopbackHost);

// A TCP connection to 127.0.0.1:port from the address `from` ("127.0.0.2": any of
// 127/8 is this machine), or -1.
int connect_from(const std::string& from, int port);

// A WebSocket client that stops reading at once: it opens /ws with the smallest
// receive buffer the kernel allows and never reads, as a stalled page would.
class StuckSocket {
 public:
  explicit StuckSocket(int port);
  ~StuckSocket();
  StuckSocket(const StuckSocket&) = delete;
  StuckSocket& operator=(const StuckSocket&) = delete;
  bool connected() const { return fd_ >= 0; }
  // Whether the server closed the connection (it reads what is buffered to find out).
  bool closed_by_server();

 private:
  int fd_ = -1;
};

class FrameCounter {
 public:
  // Connects to ws://127.0.0.1:port/ws; check connected().
  explicit FrameCounter(int port);
  ~FrameCounter();
  bool connected() const { return connection_ != nullptr; }
  // Whether the server closed the connection (a page would open another).
  bool closed() const { return closed_; }
  std::uint64_t binary_frames() const { return binary_; }
  std::uint64_t text_frames() const { return text_; }
  std::uint64_t pings() const { return pings_; }
  std::vector<std::uint8_t> last_frame();
  // From the binary frames' headers (see afhub/viewer/pose_feed.hpp): the newest
  // frame's simulation time, and how many frames went back in simulation time from
  // the frame before them in the same scene generation (0 when the feed is in order).
  double last_sim_time_s();
  std::uint64_t sim_time_reversals() const { return reversals_; }

  void on_frame(int opcode, const char* data, std::size_t length);
  void mark_closed() { closed_ = true; }

 private:
  mg_connection* connection_ = nullptr;
  std::atomic<std::uint64_t> binary_{0}, text_{0}, pings_{0}, reversals_{0};
  std::atomic<bool> closed_{false};
  std::mutex mutex_;
  std::vector<std::uint8_t> last_;
};

}  // namespace afhub::test
