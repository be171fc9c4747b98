// The simulation on the hub's channels: each active body (not `passive`) and each
// soft body publishes its state and reads its command slot; the world publishes
// its clock, counters, lights and cameras, and reads world commands.
// Commands are checked before they reach Bullet; a per-body watchdog zeroes a
// body's commands when they stop coming. Needs connect_to_hub() first.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/physics/simulation.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub::physics {

class SimChannels {
 public:
  SimChannels(Simulation& sim, double watchdog_s);

  // Reads each body's newest command, applies it, and runs the watchdogs.
  void apply_commands(std::int64_t now_ns) noexcept;
  // Publishes every body's state and the world state.
  void publish(double wall_time_s, double achieved_rate_hz, bool paused) noexcept;
  // A world command not seen before, or nullptr.
  const WorldCommand* new_world_command() noexcept;

  std::size_t channel_count() const { return channels_.size(); }
  std::uint64_t rejected_commands() const { return rejected_; }
  std::uint64_t watchdog_expiries() const { return expiries_; }

 private:
  struct Channel {
    std::size_t index = 0;  // into model bodies, or soft bodies when `soft`
    bool soft = false;
    std::unique_ptr<BodyPublisher> publisher;
    std::uint32_t joint_count = 0;
    std::uint32_t actuator_count = 0;
    std::int64_t last_command_ns = 0;
    bool commanded = false;  // a command is being applied (the watchdog is armed)
    bool told_rejected = false;
  };
  struct WorldObject {
    const WorldObjectSpec* spec = nullptr;
    int parent = -1;  // body index, or -1 for the world frame
    Pose local;
  };

  void fill_objects(std::array<WorldObjectPose, kMaxWorldObjects>& out,
                    const std::vector<WorldObject>& objects) const noexcept;

  Simulation& sim_;
  std::int64_t watchdog_ns_;
  std::vector<Channel> channels_;
  std::vector<WorldObject> lights_, cameras_;
  DirectoryPublisher directory_;
  Writer<WorldState> world_;
  LatestReader<WorldCommand> world_command_;
  std::uint64_t last_world_sequence_ = 0;
  std::uint64_t rejected_ = 0, expiries_ = 0;
};

}  // namespace afhub::physics
