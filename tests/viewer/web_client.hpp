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

HttpReply http_request(int port, const std::string& method, const std::string& target);

class FrameCounter {
 public:
  // Connects to ws://127.0.0.1:port/ws; check connected().
  explicit FrameCounter(int port);
  ~FrameCounter();
  bool connected() const { return connection_ != nullptr; }
  std::uint64_t binary_frames() const { return binary_; }
  std::uint64_t text_frames() const { return text_; }
  std::vector<std::uint8_t> last_frame();

  void on_frame(int opcode, const char* data, std::size_t length);

 private:
  mg_connection* connection_ = nullptr;
  std::atomic<std::uint64_t> binary_{0}, text_{0};
  std::mutex mutex_;
  std::vector<std::uint8_t> last_;
};

}  // namespace afhub::test
