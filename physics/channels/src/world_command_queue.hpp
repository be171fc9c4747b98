// The physics' reader of world commands: a queue, not a latest value. Several
// processes may write world commands (`afhub world`, a GUI, a test) and two that
// arrive between two reads must both be acted on, in the order they arrived; a
// latest-value reader would keep the second alone. iceoryx 2.0 merges every
// publisher's samples into the subscriber's one FIFO queue (queueCapacity > 1);
// each sample is delivered once. Internal to physics/channels.
#pragma once

#include <memory>
#include <string>

#include "afhub/shm_layout/world.hpp"

namespace afhub::physics {

class WorldCommandQueue {
 public:
  // Holds up to this many commands between two reads; older ones are dropped past it.
  static constexpr unsigned kCapacity = 64;
  explicit WorldCommandQueue(const std::string& world_instance);
  ~WorldCommandQueue();
  WorldCommandQueue(const WorldCommandQueue&) = delete;
  WorldCommandQueue& operator=(const WorldCommandQueue&) = delete;

  // The oldest valid command not read yet, copied out of shared memory into `out`;
  // false when none waits. Invalid payloads are refused (said once) and skipped.
  bool next(WorldCommand& out) noexcept;

 private:
  struct Port;
  std::unique_ptr<Port> port_;
  bool told_refused_ = false;
};

}  // namespace afhub::physics
