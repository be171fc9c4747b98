// The device and world channels of `afhub bridge dds` (--devices, --world), beside the
// bodies that dds_bridge.cpp carries.
//   Export: local device states ("device/<name>") and the world state become DDS
//   samples of "afhub/device_state" and "afhub/world_state"; with accept_commands,
//   "afhub/device_command" and "afhub/world_command" samples younger than the age
//   bound go into the local command channels.
//   Mirror: remote devices become this hub's devices (the catalog lists them as
//   devices), the remote world state is published as this hub's world, and the
//   device and world commands written here go back over DDS. Devices are claimed off
//   the loop (mirror_claims.hpp).
// World commands are each acted on once, so they travel reliably, with a short queue.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "afhub/bridges/dds_bridge.hpp"
#include "afhub/hub/bodies.hpp"
#include "afhub/hub/channel.hpp"
#include "afhub/hub/device_tape.hpp"
#include "afhub/hub/world_command_queue.hpp"
#include "afhub/shm_layout/device.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub_dds.h"
#include "mirror_claims.hpp"
#include "mirror_directory.hpp"

namespace afhub::bridges {

struct DeviceWorldCounters {
  std::uint64_t states_out = 0, states_in = 0, commands_out = 0, commands_in = 0;
  std::uint64_t stale_commands = 0, bad_samples = 0;
};

// Whether a message stamped `source_timestamp` (DDS time) is older than the bound.
inline bool too_old(dds_time_t source_timestamp, double max_age_s) {
  return static_cast<double>(dds_time() - source_timestamp) > max_age_s * 1e9;
}

class DeviceWorldBridge {
 public:
  // `directory`: the mirror's directory of this process's channels, and `claims`, which
  // claims mirrored devices (both null when not mirroring; `claims` stops before this
  // goes).
  DeviceWorldBridge(dds_entity_t participant, const DdsBridgeOptions& options,
                    MirrorDirectory* directory, MirrorClaims* claims);
  ~DeviceWorldBridge();
  DeviceWorldBridge(const DeviceWorldBridge&) = delete;
  DeviceWorldBridge& operator=(const DeviceWorldBridge&) = delete;

  // Export: new local devices of the catalog that match the device globs.
  void scan(const BodyList& catalog);
  void export_states(std::int64_t now_ns) noexcept;
  void import_commands() noexcept;
  // Mirror: remote states in, this hub's commands to them out.
  void mirror() noexcept;
  // Whether `channel` is a device this bridge mirrors (never exported back).
  bool mirrors(std::string_view channel) const noexcept;
  const DeviceWorldCounters& counters() const noexcept { return counters_; }
  std::size_t exported_devices() const noexcept { return exported_.size(); }
  std::size_t mirrored_devices() const noexcept { return mirrored_.size(); }

 private:
  struct ExportedDevice {
    std::string channel;  // device/<name>
    std::unique_ptr<LatestReader<DeviceState>> state;
    std::unique_ptr<Writer<DeviceCommand>> command;
    std::int64_t last_out_ns = 0;
  };
  struct MirroredDevice {
    std::string channel;
    std::unique_ptr<Writer<DeviceState>> state;
    std::unique_ptr<LatestReader<DeviceCommand>> command;
    std::unique_ptr<DeviceTapeWriter> tape;  // every state mirrored, for a recorder
    std::uint32_t driver_pid = 0;            // the remote driver's, and its newest sequence
    std::uint64_t driver_sequence = 0;       // through the DDS writer `relay`
    dds_instance_handle_t relay = 0;
  };
  void mirror_devices() noexcept;
  void ask_for_device(const char* channel) noexcept;
  MirrorClaims::Install claim_device(const std::string& channel);  // claims' thread
  ExportedDevice* find_exported(const char* channel) noexcept;
  MirroredDevice* find_mirrored(const char* channel) noexcept;
  void mirror_world() noexcept;

  const DdsBridgeOptions& options_;
  MirrorDirectory* directory_;  // the claims' thread's
  MirrorClaims* claims_;
  std::string world_;  // the world's channel instance
  dds_entity_t device_state_topic_ = 0, device_command_topic_ = 0;
  dds_entity_t world_state_topic_ = 0, world_command_topic_ = 0;
  dds_entity_t device_state_writer_ = 0, device_command_reader_ = 0;
  dds_entity_t device_state_reader_ = 0, device_command_writer_ = 0;
  dds_entity_t world_state_writer_ = 0, world_command_reader_ = 0;
  dds_entity_t world_state_reader_ = 0, world_command_writer_ = 0;
  afhub_dds_DeviceState device_state_sample_{};
  afhub_dds_DeviceCommand device_command_sample_{};
  afhub_dds_WorldState world_state_sample_{};
  afhub_dds_WorldCommand world_command_sample_{};
  std::vector<ExportedDevice> exported_;
  std::set<std::string> not_exported_;  // refused a port, said once
  std::vector<MirroredDevice> mirrored_;
  // Export: the local world's state and command channels; mirror: the remote world's.
  std::unique_ptr<LatestReader<WorldState>> world_state_in_;
  std::unique_ptr<Writer<WorldCommand>> world_command_out_;
  std::unique_ptr<Writer<WorldState>> world_state_out_;
  std::unique_ptr<WorldCommandQueue> world_commands_;
  std::int64_t world_last_out_ns_ = 0;
  DeviceWorldCounters counters_;
};

}  // namespace afhub::bridges
