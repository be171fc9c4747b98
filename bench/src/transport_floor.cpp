// shm-floor: the machine's floor for afhub's slots, bare shared memory between the two
// processes and no afhub code. Each direction is a lane of one shared file; its writer
// fills the payload, then the stamps and, last, the round number (a release store in the
// stamps' cache line), and its reader polls the round number and reads the rest in
// place. A message here costs moving its cache lines from one CPU to the other, which
// every shared-memory transport pays: afhub-slot's distance from it is afhub's own.
//
// Unlike a slot, a lane has no guard against being rewritten while it is read: the
// ping-pong keeps writer and reader apart. The pong side writes only in answer to a new
// ping, which the ping side writes only once its last one was answered (a handshake's
// repeated pings while the peer starts are dropped instead).
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

#include "afhub/shm_layout/error.hpp"
#include "transport.hpp"

namespace afhub::bench {
namespace {

struct LaneHead {
  std::atomic<std::uint64_t> round;  // stored last
  std::uint32_t bytes;               // the whole message, this head included
  std::uint32_t unused;
  std::int64_t send_ns;
  std::int64_t peer_receive_ns;
};
static_assert(sizeof(LaneHead) == 32 && sizeof(LaneHead) <= kMinPayloadBytes);
static_assert(std::atomic<std::uint64_t>::is_always_lock_free);

constexpr std::size_t kLaneBytes = kMaxPayloadBytes;  // page-aligned: each lane's head is too
constexpr std::size_t kFileBytes = 2 * kLaneBytes;

std::string file_name(const std::string& session) {
  return "/afhub-bench-" + session + "-floor";
}

[[noreturn]] void fail_floor(const std::string& what) {
  throw Error("shm-floor: " + what + ": " + std::strerror(errno));
}

// As fail_floor, closing `fd` first (errno kept: it says why).
[[noreturn]] void fail_closing(int fd, const std::string& what) {
  const int error = errno;
  close(fd);
  errno = error;
  fail_floor(what);
}

class FloorTransport : public Transport {
 public:
  FloorTransport(Side side, const std::string& session) : side_(side), name_(file_name(session)) {
    if (side_ == Side::kPing) {
      // The ping side makes the file; the peer opens it once started (connect). A file of
      // this name is an earlier bench's of the same pid, killed: replaced.
      shm_unlink(name_.c_str());
      const int fd = shm_open(name_.c_str(), O_CREAT | O_EXCL | O_RDWR | O_CLOEXEC, 0600);
      if (fd < 0) fail_floor("cannot make /dev/shm" + name_);
      try {
        if (ftruncate(fd, kFileBytes) != 0) fail_closing(fd, "cannot size /dev/shm" + name_);
        map(fd);
      } catch (...) {
        shm_unlink(name_.c_str());
        throw;
      }
      owner_ = true;
    }
  }

  ~FloorTransport() override {
    if (base_) munmap(base_, kFileBytes);
    if (owner_) shm_unlink(name_.c_str());
  }

  void connect(std::int64_t deadline_ns) override {
    if (side_ == Side::kPing) return;
    int fd;
    while ((fd = shm_open(name_.c_str(), O_RDWR | O_CLOEXEC, 0)) < 0) {
      if (errno != ENOENT) fail_floor("cannot open /dev/shm" + name_);
      if (monotonic_ns() > deadline_ns) fail_floor("the bench made no /dev/shm" + name_);
      usleep(10'000);
    }
    struct stat status {};
    if (fstat(fd, &status) != 0) fail_closing(fd, "cannot look at /dev/shm" + name_);
    if (static_cast<std::size_t>(status.st_size) != kFileBytes) {
      close(fd);
      throw Error("shm-floor: /dev/shm" + name_ + " is not the bench's file (its size is " +
                  std::to_string(status.st_size) + " bytes)");
    }
    map(fd);
  }

  std::int64_t send(std::uint32_t bytes, std::uint64_t round,
                    std::int64_t peer_receive_ns) override {
    const std::int64_t send_ns = monotonic_ns();
    if (side_ == Side::kPing && written_ != answered_) return send_ns;  // the peer still reads
    touch_written(reinterpret_cast<char*>(out_ + 1), bytes - sizeof(LaneHead), round);
    out_->bytes = bytes;
    out_->send_ns = send_ns;
    out_->peer_receive_ns = peer_receive_ns;
    out_->round.store(round, std::memory_order_release);
    written_ = round;
    return send_ns;
  }

  std::optional<Message> receive(std::int64_t deadline_ns) override {
    for (;;) {
      const std::uint64_t round = in_->round.load(std::memory_order_acquire);
      if (round != seen_) {
        seen_ = round;
        if (round == written_) answered_ = round;
        // The other process's number, read once (volatile: never again) and checked.
        const std::uint32_t bytes = *static_cast<volatile const std::uint32_t*>(&in_->bytes);
        if (bytes < sizeof(LaneHead) || bytes > kLaneBytes)
          throw Error("shm-floor: a message of " + std::to_string(bytes) +
                      " bytes is out of range");
        touch_read(reinterpret_cast<const char*>(in_ + 1), bytes - sizeof(LaneHead), round,
                   "shm-floor");
        return Message{bytes, round, in_->send_ns, in_->peer_receive_ns, monotonic_ns()};
      }
      if (monotonic_ns() > deadline_ns) return std::nullopt;
    }
  }

 private:
  void map(int fd) {
    void* mapped = mmap(nullptr, kFileBytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    if (mapped == MAP_FAILED) fail_closing(fd, "cannot map /dev/shm" + name_);
    close(fd);
    base_ = static_cast<char*>(mapped);
    // Lane 0 carries pings, lane 1 pongs.
    const auto lane = [&](std::size_t i) {
      return reinterpret_cast<LaneHead*>(base_ + i * kLaneBytes);
    };
    out_ = lane(side_ == Side::kPing ? 0 : 1);
    in_ = lane(side_ == Side::kPing ? 1 : 0);
  }

  Side side_;
  std::string name_;
  bool owner_ = false;
  char* base_ = nullptr;
  LaneHead* out_ = nullptr;
  LaneHead* in_ = nullptr;
  std::uint64_t seen_ = 0;      // the last round read from the other lane (rounds start at 1)
  std::uint64_t written_ = 0;   // the last round written to ours
  std::uint64_t answered_ = 0;  // the last of ours the peer answered (ping side)
};

}  // namespace

std::unique_ptr<Transport> open_floor_transport(Side side, const std::string& session) {
  return std::make_unique<FloorTransport>(side, session);
}

}  // namespace afhub::bench
