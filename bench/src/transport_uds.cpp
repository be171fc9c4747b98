// Unix domain stream sockets: the fastest kernel path between two processes. Each
// message is written and read whole, its stamps in a 32-byte frame header; both
// ends poll non-blocking sockets, as the afhub ends poll their channels.
#include <errno.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstring>
#include <vector>

#include "afhub/shm_layout/error.hpp"
#include "transport.hpp"

namespace afhub::bench {
namespace {

struct Frame {
  std::uint32_t bytes;  // the whole message, this frame included
  std::uint32_t reserved;
  std::uint64_t round;
  std::int64_t send_ns;
  std::int64_t peer_receive_ns;
};
static_assert(sizeof(Frame) == 32 && sizeof(Frame) <= kMinPayloadBytes);

std::string socket_path(const std::string& session) {
  return "/tmp/afhub-bench-" + session + ".sock";
}

sockaddr_un address_of(const std::string& path) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::strncpy(address.sun_path, path.c_str(), sizeof address.sun_path - 1);
  return address;
}

[[noreturn]] void fail(const std::string& what) {
  throw Error("uds: " + what + ": " + std::strerror(errno));
}

class UdsTransport : public Transport {
 public:
  UdsTransport(Side side, const std::string& session)
      : side_(side), path_(socket_path(session)), buffer_(kMaxPayloadBytes) {
    if (side_ == Side::kPing) {
      // The ping side listens; the peer connects once started.
      listener_ = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0);
      if (listener_ < 0) fail("socket");
      unlink(path_.c_str());
      const sockaddr_un address = address_of(path_);
      if (bind(listener_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0)
        fail("bind " + path_);
      if (listen(listener_, 1) != 0) fail("listen");
    }
  }

  ~UdsTransport() override {
    if (fd_ >= 0) close(fd_);
    if (listener_ >= 0) {
      close(listener_);
      unlink(path_.c_str());
    }
  }

  void connect(std::int64_t deadline_ns) override {
    if (side_ == Side::kPing) {
      while ((fd_ = accept4(listener_, nullptr, nullptr, SOCK_NONBLOCK)) < 0) {
        if (errno != EAGAIN && errno != EINTR) fail("accept");
        if (monotonic_ns() > deadline_ns) throw Error("uds: the peer did not connect");
        usleep(1'000);
      }
      return;
    }
    const sockaddr_un address = address_of(path_);
    for (;;) {
      fd_ = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0);
      if (fd_ < 0) fail("socket");
      if (::connect(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0) return;
      close(fd_);
      fd_ = -1;
      if (monotonic_ns() > deadline_ns) fail("connect " + path_);
      usleep(10'000);
    }
  }

  std::int64_t send(std::uint32_t bytes, std::uint64_t round,
                    std::int64_t peer_receive_ns) override {
    Frame frame{bytes, 0, round, monotonic_ns(), peer_receive_ns};
    std::memcpy(buffer_.data(), &frame, sizeof frame);
    touch_written(buffer_.data() + sizeof frame, bytes - sizeof frame, round);
    for (std::size_t sent = 0; sent < bytes;) {
      const ssize_t n = ::send(fd_, buffer_.data() + sent, bytes - sent, MSG_NOSIGNAL);
      if (n > 0) {
        sent += static_cast<std::size_t>(n);
      } else if (n < 0 && errno != EAGAIN && errno != EINTR) {
        fail("send");
      }
    }
    return frame.send_ns;
  }

  std::optional<Message> receive(std::int64_t deadline_ns) override {
    if (!read_exactly(0, sizeof(Frame), deadline_ns)) return std::nullopt;
    Frame frame;
    std::memcpy(&frame, buffer_.data(), sizeof frame);
    if (frame.bytes < sizeof frame || frame.bytes > kMaxPayloadBytes)
      throw Error("uds: a frame of " + std::to_string(frame.bytes) + " bytes is out of range");
    // A message once begun is read to its end, whatever the deadline.
    read_exactly(sizeof frame, frame.bytes, 0);
    touch_read(buffer_.data() + sizeof frame, frame.bytes - sizeof frame, frame.round, "uds");
    return Message{frame.bytes, frame.round, frame.send_ns, frame.peer_receive_ns, monotonic_ns()};
  }

 private:
  // Reads buffer_[from, to). False when nothing came before the deadline
  // (deadline 0: wait as long as it takes).
  bool read_exactly(std::size_t from, std::size_t to, std::int64_t deadline_ns) {
    for (std::size_t got = from; got < to;) {
      const ssize_t n = recv(fd_, buffer_.data() + got, to - got, MSG_DONTWAIT);
      if (n > 0) {
        got += static_cast<std::size_t>(n);
      } else if (n == 0) {
        throw Error("uds: the other end closed the socket");
      } else if (errno != EAGAIN && errno != EINTR) {
        fail("recv");
      } else if (got == from && deadline_ns != 0 && monotonic_ns() > deadline_ns) {
        return false;
      }
    }
    return true;
  }

  Side side_;
  std::string path_;
  std::vector<char> buffer_;
  int listener_ = -1;
  int fd_ = -1;
};

}  // namespace

std::unique_ptr<Transport> open_uds_transport(Side side, const std::string& session) {
  return std::make_unique<UdsTransport>(side, session);
}

}  // namespace afhub::bench
