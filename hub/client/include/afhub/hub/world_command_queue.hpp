// The reader of world commands for whoever runs a world (the physics, `afhub synth`):
// a queue, not a latest value. Several processes may write world commands (`afhub
// world`, a GUI, a test) and two that arrive between two reads must both be acted on,
// in the order they arrived; a latest-value reader would keep the second alone.
// iceoryx 2.0 merges every publisher's samples into the subscriber's one FIFO queue
// (queueCapacity > 1); each sample is delivered once.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "afhub/shm_layout/world.hpp"

namespace afhub {

class WorldCommandQueue {
 public:
  // Holds up to this many commands between two reads; older ones are dropped past it.
  static constexpr unsigned kCapacity = 64;
  explicit WorldCommandQueue(const std::string& world_instance);
  ~WorldCommandQueue();
  WorldCommandQueue(const WorldCommandQueue&) = delete;
  WorldCommandQueue& operator=(const WorldCommandQueue&) = delete;

  // The oldest valid command not read yet, copied out of shared memory into `out`;
  // false when none waits. Invalid payloads are refused (said once) and skipped, and
  // so are repeats and commands published before this queue was made (history from
  // a writer that outlived an earlier world): each command is acted on exactly once.
  // A command read past its valid_ms is skipped and said.
  bool next(WorldCommand& out) noexcept;

 private:
  bool seen(const PayloadHeader& header) noexcept;
  bool expired(const WorldCommand& command) noexcept;
  static constexpr unsigned kExpiredSaid = 4;
  unsigned expired_said_ = 0;

  struct Port;
  std::unique_ptr<Port> port_;
  std::int64_t created_ns_;
  bool told_refused_ = false;
  // The last command taken from each recent writer.
  struct Writer {
    std::uint32_t pid = 0;
    std::uint64_t sequence = 0;
    std::int64_t stamp_ns = 0;
  };
  std::array<Writer, 32> writers_{};
  std::size_t next_writer_ = 0;  // the slot a new writer takes (the oldest)
};

}  // namespace afhub
