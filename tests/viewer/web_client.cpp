// The tests' HTTP and WebSocket clients (see web_client.hpp).
#include "web_client.hpp"

#include <arpa/inet.h>
#include <civetweb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace afhub::test {

int connect_from(const std::string& from, int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  sockaddr_in source{};
  source.sin_family = AF_INET;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if ((!from.empty() && (inet_pton(AF_INET, from.c_str(), &source.sin_addr) != 1 ||
                         bind(fd, reinterpret_cast<sockaddr*>(&source), sizeof source) != 0)) ||
      connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

HttpReply http_request(int port, const std::string& method, const std::string& target,
                       const std::string& from, const std::string& headers) {
  HttpReply reply;
  const int fd = connect_from(from, port);
  if (fd < 0) return reply;
  timeval timeout{5, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  const std::string request = method + " " + target + " HTTP/1.1\r\n" + headers +
                              "Content-Length: 0\r\nConnection: close\r\n\r\n";
  if (write(fd, request.data(), request.size()) != static_cast<ssize_t>(request.size())) {
    close(fd);
    return reply;
  }
  std::string raw;
  char buffer[65536];
  for (ssize_t n; (n = read(fd, buffer, sizeof buffer)) > 0;) raw.append(buffer, n);
  close(fd);
  // "HTTP/1.1 200 OK\r\n...\r\n\r\nbody"
  if (raw.rfind("HTTP/1.", 0) != 0 || raw.size() < 12) return reply;
  reply.status = std::atoi(raw.c_str() + 9);
  const std::size_t body = raw.find("\r\n\r\n");
  if (body != std::string::npos) reply.body = raw.substr(body + 4);
  return reply;
}

StuckSocket::StuckSocket(int port) {
  fd_ = socket(AF_INET, SOCK_STREAM, 0);
  if (fd_ < 0) return;
  const int smallest = 1;  // the kernel rounds it up to its minimum
  setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &smallest, sizeof smallest);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const std::string upgrade =
      "GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
      "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
  if (connect(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
      write(fd_, upgrade.data(), upgrade.size()) != static_cast<ssize_t>(upgrade.size())) {
    close(fd_);
    fd_ = -1;
  }
}

StuckSocket::~StuckSocket() {
  if (fd_ >= 0) close(fd_);
}

bool StuckSocket::closed_by_server() {
  char buffer[65536];
  for (;;) {
    const ssize_t n = recv(fd_, buffer, sizeof buffer, MSG_DONTWAIT);
    if (n == 0) return true;
    if (n < 0) return errno != EAGAIN && errno != EWOULDBLOCK;
  }
}

namespace {

int on_data(mg_connection*, int flags, char* data, size_t length, void* counter) {
  static_cast<FrameCounter*>(counter)->on_frame(flags & 0x0f, data, length);
  return 1;
}

void on_close(const mg_connection*, void* counter) {
  static_cast<FrameCounter*>(counter)->mark_closed();
}

}  // namespace

FrameCounter::FrameCounter(int port) {
  mg_init_library(0);
  char error[256] = "";
  connection_ = mg_connect_websocket_client("127.0.0.1", port, 0, error, sizeof error, "/ws",
                                            nullptr, on_data, on_close, this);
}

FrameCounter::~FrameCounter() {
  if (connection_) mg_close_connection(connection_);
  mg_exit_library();
}

void FrameCounter::on_frame(int opcode, const char* data, std::size_t length) {
  if (opcode == MG_WEBSOCKET_OPCODE_PING) {
    // Answered as browsers do: the server drops a page that leaves pings unanswered.
    ++pings_;
    mg_websocket_client_write(connection_, MG_WEBSOCKET_OPCODE_PONG, data, length);
  } else if (opcode == MG_WEBSOCKET_OPCODE_BINARY) {
    std::lock_guard lock(mutex_);
    if (length >= 24 && last_.size() >= 24) {
      std::uint32_t generation = 0, last_generation = 0;
      double sim_time_s = 0.0, last_sim_time_s = 0.0;
      std::memcpy(&generation, data + 4, 4);
      std::memcpy(&last_generation, last_.data() + 4, 4);
      std::memcpy(&sim_time_s, data + 16, 8);
      std::memcpy(&last_sim_time_s, last_.data() + 16, 8);
      if (generation == last_generation && sim_time_s < last_sim_time_s) ++reversals_;
    }
    last_.assign(data, data + length);
    ++binary_;
  } else if (opcode == MG_WEBSOCKET_OPCODE_TEXT) {
    ++text_;
  }
}

double FrameCounter::last_sim_time_s() {
  std::lock_guard lock(mutex_);
  double sim_time_s = 0.0;
  if (last_.size() >= 24) std::memcpy(&sim_time_s, last_.data() + 16, 8);
  return sim_time_s;
}

std::vector<std::uint8_t> FrameCounter::last_frame() {
  std::lock_guard lock(mutex_);
  return last_;
}

}  // namespace afhub::test
