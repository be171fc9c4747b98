// Device and world channels over DDS (see dds_device_world.hpp). As for bodies, the
// steady state allocates nothing here: samples are made once, devices are looked up
// in vectors made when they appear.
#include "dds_device_world.hpp"

#include <cstdio>
#include <cstring>

#include "afhub/hub/body_claims.hpp"
#include "afhub/hub/hub_health.hpp"
#include "afhub/shm_layout/error.hpp"
#include "dds_convert_device_world.hpp"
#include "dds_entity.hpp"

namespace afhub::bridges {
namespace {

constexpr const char* kDeviceStateTopic = "afhub/device_state";
constexpr const char* kDeviceCommandTopic = "afhub/device_command";
constexpr const char* kWorldStateTopic = "afhub/world_state";
constexpr const char* kWorldCommandTopic = "afhub/world_command";
constexpr std::string_view kDevicePrefix = "device/";
// World commands queued on the way: more than anyone types between two bridge cycles.
constexpr int kWorldCommandDepth = 16;

dds_entity_t topic(dds_entity_t participant, const dds_topic_descriptor_t& type, const char* name) {
  return checked(dds_create_topic(participant, &type, name, nullptr, nullptr),
                 (std::string("creating the topic ") + name).c_str());
}

// A device's name as the globs see it: "device/<name>" without "device/".
std::string_view device_name_of(std::string_view channel) {
  return channel.substr(kDevicePrefix.size());
}

// Whether a sample may go out now under a per-topic rate limit (0: no limit).
bool rate_allows(std::int64_t now_ns, std::int64_t& last_ns, double rate_hz) {
  if (rate_hz > 0.0 && static_cast<double>(now_ns - last_ns) < 1e9 / rate_hz) return false;
  last_ns = now_ns;
  return true;
}

}  // namespace

DeviceWorldBridge::DeviceWorldBridge(dds_entity_t participant, const DdsBridgeOptions& options,
                                     MirrorDirectory* directory, MirrorClaims* claims)
    : options_(options), directory_(directory), claims_(claims), world_(world_instance()) {
  const bool devices = !options.device_globs.empty();
  const Qos stream, commands;
  set_stream_qos(stream.get(), options.reliable);
  set_ignore_own(stream.get());
  set_queue_qos(commands.get(), kWorldCommandDepth);
  set_ignore_own(commands.get());
  if (devices) {
    device_state_topic_ = topic(participant, afhub_dds_DeviceState_desc, kDeviceStateTopic);
    device_command_topic_ = topic(participant, afhub_dds_DeviceCommand_desc, kDeviceCommandTopic);
  }
  if (options.world) {
    world_state_topic_ = topic(participant, afhub_dds_WorldState_desc, kWorldStateTopic);
    world_command_topic_ = topic(participant, afhub_dds_WorldCommand_desc, kWorldCommandTopic);
  }
  if (options.export_bodies) {
    if (devices) {
      device_state_writer_ =
          checked(dds_create_writer(participant, device_state_topic_, stream.get(), nullptr),
                  "device state writer");
      if (options.accept_commands)
        device_command_reader_ =
            checked(dds_create_reader(participant, device_command_topic_, stream.get(), nullptr),
                    "device command reader");
    }
    if (options.world) {
      world_state_writer_ =
          checked(dds_create_writer(participant, world_state_topic_, stream.get(), nullptr),
                  "world state writer");
      world_state_in_ = std::make_unique<LatestReader<WorldState>>(
          ChannelId{std::string(kService), world_, std::string(kStateEvent)});
      if (options.accept_commands) {
        world_command_reader_ =
            checked(dds_create_reader(participant, world_command_topic_, commands.get(), nullptr),
                    "world command reader");
        world_command_out_ = std::make_unique<Writer<WorldCommand>>(
            ChannelId{std::string(kService), world_, std::string(kCommandEvent)});
        // World commands are acted on once per (pid, sequence): start past any number
        // an earlier bridge of this pid could have used.
        world_command_out_->raw().continue_sequence_after(
            static_cast<std::uint64_t>(monotonic_ns()));
      }
    }
  }
  if (options.mirror) {
    if (devices) {
      device_state_reader_ =
          checked(dds_create_reader(participant, device_state_topic_, stream.get(), nullptr),
                  "device state reader");
      device_command_writer_ =
          checked(dds_create_writer(participant, device_command_topic_, stream.get(), nullptr),
                  "device command writer");
    }
    if (options.world) {
      world_state_reader_ =
          checked(dds_create_reader(participant, world_state_topic_, stream.get(), nullptr),
                  "world state reader");
      world_command_writer_ =
          checked(dds_create_writer(participant, world_command_topic_, commands.get(), nullptr),
                  "world command writer");
      require_chunks({written_as_slot(sizeof(WorldState))},
                     "afhub bridge dds (the world's state, --world)");
      world_state_out_ = std::make_unique<Writer<WorldState>>(
          ChannelId{std::string(kService), world_, std::string(kStateEvent)});
      world_commands_ = std::make_unique<WorldCommandQueue>(world_);
    }
  }
  make_world_state_sample(world_state_sample_);
}

DeviceWorldBridge::~DeviceWorldBridge() {
  free_world_state_sample(world_state_sample_);
}

bool DeviceWorldBridge::mirrors(std::string_view channel) const noexcept {
  for (const MirroredDevice& device : mirrored_)
    if (device.channel == channel) return true;
  return false;
}

DeviceWorldBridge::ExportedDevice* DeviceWorldBridge::find_exported(const char* channel) noexcept {
  for (ExportedDevice& device : exported_)
    if (device.channel == channel) return &device;
  return nullptr;
}

DeviceWorldBridge::MirroredDevice* DeviceWorldBridge::find_mirrored(const char* channel) noexcept {
  for (MirroredDevice& device : mirrored_)
    if (device.channel == channel) return &device;
  return nullptr;
}

void DeviceWorldBridge::scan(const BodyList& catalog) {
  if (!device_state_writer_) return;
  for (std::uint32_t i = 0; i < catalog.body_count; ++i) {
    const BodyInfo& info = catalog.bodies[i];
    if (info.kind != ChannelKind::kDevice) continue;
    const std::string channel(name_of(info.channel));
    if (channel.rfind(kDevicePrefix, 0) != 0 || mirrors(channel) ||
        find_exported(channel.c_str()) ||
        !matches_any(std::string(device_name_of(channel)), options_.device_globs))
      continue;
    // No iceoryx port left for it: said once, tried again on the next scan.
    try {
      ExportedDevice device{
          channel, std::make_unique<LatestReader<DeviceState>>(body_state_channel(channel)),
          std::make_unique<Writer<DeviceCommand>>(body_command_channel(channel))};
      exported_.push_back(std::move(device));
    } catch (const Error& error) {
      if (not_exported_.insert(channel).second)
        std::fprintf(stderr, "afhub bridge dds: not exporting device %s: %s\n", channel.c_str(),
                     error.what());
      continue;
    }
    std::fprintf(stderr, "afhub bridge dds: exporting device %s\n", channel.c_str());
  }
}

void DeviceWorldBridge::export_states(std::int64_t now_ns) noexcept {
  for (ExportedDevice& device : exported_) {
    const DeviceState* state = device.state->latest();
    if (!state || !device.state->updated() ||
        !rate_allows(now_ns, device.last_out_ns, options_.device_rate_hz))
      continue;
    to_dds(device.channel, *state, device_state_sample_);
    if (dds_write(device_state_writer_, &device_state_sample_) >= 0) ++counters_.states_out;
  }
  if (world_state_in_) {
    const WorldState* state = world_state_in_->latest();
    if (state && world_state_in_->updated() &&
        rate_allows(now_ns, world_last_out_ns_, options_.world_rate_hz)) {
      to_dds(world_, *state, world_state_sample_);
      if (dds_write(world_state_writer_, &world_state_sample_) >= 0) ++counters_.states_out;
    }
  }
}

// Only with accept_commands; a command older than the bound by its DDS source
// timestamp is dropped, never applied late.
void DeviceWorldBridge::import_commands() noexcept {
  dds_sample_info_t info;
  if (device_command_reader_) {
    void* samples[1] = {&device_command_sample_};
    while (dds_take(device_command_reader_, samples, &info, 1, 1) > 0) {
      if (!info.valid_data) continue;
      if (too_old(info.source_timestamp, options_.max_command_age_s)) {
        ++counters_.stale_commands;
        continue;
      }
      ExportedDevice* device = find_exported(device_command_sample_.device);
      if (!device) continue;
      DeviceCommand* command = device->command->loan();
      if (!command) continue;
      from_dds(device_command_sample_, *command);
      device->command->publish(command);
      ++counters_.commands_in;
    }
  }
  if (world_command_reader_) {
    void* samples[1] = {&world_command_sample_};
    while (dds_take(world_command_reader_, samples, &info, 1, 1) > 0) {
      if (!info.valid_data || world_ != world_command_sample_.world) continue;
      if (too_old(info.source_timestamp, options_.max_command_age_s)) {
        ++counters_.stale_commands;
        continue;
      }
      WorldCommand* command = world_command_out_->loan();
      if (!command) continue;
      if (!from_dds(world_command_sample_, *command)) {
        ++counters_.bad_samples;
        command->action = WorldAction::kNone;  // a loaned chunk goes out doing nothing
      } else {
        ++counters_.commands_in;
      }
      world_command_out_->publish(command);
    }
  }
}

// A new remote device (its spec comes in every state): asked for once, not per
// message; its states are dropped until it is in place.
void DeviceWorldBridge::ask_for_device(const char* channel) noexcept {
  const std::string_view text(channel);
  if (claims_->drop_if_pending(text) || text.rfind(kDevicePrefix, 0) != 0) return;
  try {
    if (!matches_any(std::string(device_name_of(text)), options_.device_globs) ||
        !claims_->may_ask(text))
      return;
    const std::string name(text);
    claims_->ask(name, [this, name] { return claim_device(name); });
  } catch (const std::exception&) {
    // Out of memory: asked again with the next state.
  }
}

// On the claims' thread: a device that does not fit is refused.
MirrorClaims::Install DeviceWorldBridge::claim_device(const std::string& channel) {
  const BodyEntry entry = make_device_entry(device_name_of(channel));
  directory_->check_room(entry);
  check_room_for_bodies({channel}, 1);
  require_chunks({written_as_slot(sizeof(DeviceState))}, "mirroring " + channel);
  auto device = std::make_shared<MirroredDevice>(
      MirroredDevice{channel, std::make_unique<Writer<DeviceState>>(body_state_channel(channel)),
                     std::make_unique<LatestReader<DeviceCommand>>(body_command_channel(channel)),
                     std::make_unique<DeviceTapeWriter>(channel)});
  directory_->add(entry);
  return [this, device] {
    mirrored_.push_back(std::move(*device));
    std::fprintf(stderr, "afhub bridge dds: mirroring device %s\n",
                 mirrored_.back().channel.c_str());
  };
}

void DeviceWorldBridge::mirror_devices() noexcept {
  dds_sample_info_t info;
  void* samples[1] = {&device_state_sample_};
  while (dds_take(device_state_reader_, samples, &info, 1, 1) > 0) {
    if (!info.valid_data) continue;
    const char* channel = device_state_sample_.device;
    MirroredDevice* device = find_mirrored(channel);
    if (!device) {
      ask_for_device(channel);
      continue;
    }
    DeviceState* state = device->state->loan();
    if (!state) continue;
    // A driver restarted on the other machine is numbered afresh here too: its readers
    // (teleop) know a new driver by its pid or its numbering, and the mirror's pid does
    // not change (a palm was thrown to the new driver's hand). Its numbering goes back
    // only through one relay: two bridges relaying one driver interleave theirs.
    const afhub_dds_Header& remote = device_state_sample_.header;
    if (device->driver_pid != 0 && (remote.publisher_pid != device->driver_pid ||
                                    (info.publication_handle == device->relay &&
                                     remote.sequence_number < device->driver_sequence)))
      device->state->raw().continue_sequence_after(0);
    device->driver_pid = remote.publisher_pid;
    device->driver_sequence = remote.sequence_number;
    device->relay = info.publication_handle;
    if (!from_dds(device_state_sample_, *state)) {
      ++counters_.bad_samples;
      state->gate = ForceGate::kNoCommand;  // a loaned chunk must go somewhere
    }
    device->state->publish(state);
    device->tape->add(*state, nullptr);
    ++counters_.states_in;
  }
  // Commands written here to mirrored devices go to their driver, stamped with their
  // age: the DDS source timestamp is when the local writer published.
  for (MirroredDevice& device : mirrored_) {
    const DeviceCommand* command = device.command->latest();
    if (!command || !device.command->updated()) continue;
    to_dds(device.channel, *command, device_command_sample_);
    const std::int64_t age_ns =
        std::max<std::int64_t>(0, monotonic_ns() - command->header.publish_stamp_ns);
    if (dds_write_ts(device_command_writer_, &device_command_sample_, dds_time() - age_ns) >= 0)
      ++counters_.commands_out;
  }
}

void DeviceWorldBridge::mirror_world() noexcept {
  dds_sample_info_t info;
  void* samples[1] = {&world_state_sample_};
  while (dds_take(world_state_reader_, samples, &info, 1, 1) > 0) {
    if (!info.valid_data || world_ != world_state_sample_.world) continue;
    WorldState* state = world_state_out_->loan();
    if (!state) continue;
    from_dds(world_state_sample_, *state);
    world_state_out_->publish(state);
    ++counters_.states_in;
  }
  WorldCommand command;
  while (world_commands_->next(command)) {
    to_dds(world_, command, world_command_sample_);
    const std::int64_t age_ns =
        std::max<std::int64_t>(0, monotonic_ns() - command.header.publish_stamp_ns);
    if (dds_write_ts(world_command_writer_, &world_command_sample_, dds_time() - age_ns) >= 0)
      ++counters_.commands_out;
  }
}

void DeviceWorldBridge::mirror() noexcept {
  if (device_state_reader_) mirror_devices();
  if (world_state_reader_) mirror_world();
}

}  // namespace afhub::bridges
