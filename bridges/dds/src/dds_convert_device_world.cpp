// Device and world payloads to and from afhub's DDS types (see dds_convert_device_world.hpp).
#include "dds_convert_device_world.hpp"

#include <algorithm>

#include "dds_convert_parts.hpp"

namespace afhub::bridges {
namespace {

void poses_out(const std::array<WorldObjectPose, kMaxWorldObjects>& from, std::uint32_t count,
               dds_sequence_afhub_dds_WorldObjectPose& to) noexcept {
  to._length = std::min<std::uint32_t>({count, kMaxWorldObjects, to._maximum});
  for (std::uint32_t i = 0; i < to._length; ++i) {
    copy_text(from[i].name.data(), from[i].name.size(), to._buffer[i].name);
    to._buffer[i].pose = to_dds(from[i].pose);
  }
}
std::uint32_t poses_in(const dds_sequence_afhub_dds_WorldObjectPose& from,
                       std::array<WorldObjectPose, kMaxWorldObjects>& to) noexcept {
  const std::uint32_t count = std::min<std::uint32_t>(from._length, kMaxWorldObjects);
  for (std::uint32_t i = 0; i < count; ++i) {
    copy_text(from._buffer[i].name, to[i].name);
    to[i].pose = from_dds(from._buffer[i].pose);
  }
  return count;
}

// The fields named and typed alike in afhub's payload and its DDS type, copied either
// way: one list for both directions, so that they cannot disagree.
template <typename From, typename To>
void copy_device_values(const From& from, To& to) noexcept {
  to.spec.max_force_n = from.spec.max_force_n;
  to.spec.max_torque_nm = from.spec.max_torque_nm;
  to.spec.max_gripper_force_n = from.spec.max_gripper_force_n;
  to.spec.max_stiffness_npm = from.spec.max_stiffness_npm;
  to.spec.workspace_radius_m = from.spec.workspace_radius_m;
  to.spec.sensed = from.spec.sensed;
  to.spec.actuated = from.spec.actuated;
  to.spec.button_count = from.spec.button_count;
  to.gripper_angle_rad = from.gripper_angle_rad;
  to.buttons = from.buttons;
  to.applied_gripper_force_n = from.applied_gripper_force_n;
  to.command_sequence = from.command_sequence;
  to.command_stamp_ns = from.command_stamp_ns;
}
template <typename From, typename To>
void copy_world_values(const From& from, To& to) noexcept {
  to.wall_time_s = from.wall_time_s;
  to.achieved_rate_hz = from.achieved_rate_hz;
  to.body_count = from.body_count;
  to.paused = from.paused;
  to.lockstep = from.lockstep;
  to.pause_held = from.pause_held;
  to.paused_by_pid = from.paused_by_pid;
  to.rejected_commands = from.rejected_commands;
  to.watchdog_expiries = from.watchdog_expiries;
  to.stale_commands = from.stale_commands;
  to.lockstep_clients = from.lockstep_clients;
  to.late_answers = from.late_answers;
  to.dropped_clients = from.dropped_clients;
  to.commanded_steps = from.commanded_steps;
  to.answered_steps = from.answered_steps;
  to.nan_recoveries = from.nan_recoveries;
  to.last_nan_step = from.last_nan_step;
}

}  // namespace

void make_world_state_sample(afhub_dds_WorldState& sample) {
  sample = {};
  reserve(sample.lights, kMaxWorldObjects);
  reserve(sample.cameras, kMaxWorldObjects);
}

void free_world_state_sample(afhub_dds_WorldState& sample) {
  dds_sample_free(&sample, &afhub_dds_WorldState_desc, DDS_FREE_CONTENTS);
}

void to_dds(std::string_view channel, const DeviceState& state,
            afhub_dds_DeviceState& sample) noexcept {
  copy_text(channel, sample.device);
  sample.header = to_dds(state.header);
  copy_text(state.spec.model.data(), state.spec.model.size(), sample.spec.model);
  copy_text(state.spec.serial.data(), state.spec.serial.size(), sample.spec.serial);
  copy_device_values(state, sample);
  sample.pose = to_dds(state.pose);
  sample.velocity = to_dds(state.velocity);
  sample.gate = static_cast<std::uint8_t>(state.gate);
  sample.applied = to_dds(state.applied);
}

bool from_dds(const afhub_dds_DeviceState& sample, DeviceState& state) noexcept {
  if (sample.gate > static_cast<std::uint8_t>(ForceGate::kStopping)) return false;
  from_dds(sample.header, state.header);
  copy_text(sample.spec.model, state.spec.model);
  copy_text(sample.spec.serial, state.spec.serial);
  copy_device_values(sample, state);
  state.pose = from_dds(sample.pose);
  state.velocity = from_dds(sample.velocity);
  state.gate = static_cast<ForceGate>(sample.gate);
  state.applied = from_dds(sample.applied);
  return true;
}

void to_dds(std::string_view channel, const DeviceCommand& command,
            afhub_dds_DeviceCommand& sample) noexcept {
  copy_text(channel, sample.device);
  sample.header = to_dds(command.header);
  sample.wrench = to_dds(command.wrench);
  sample.gripper_force_n = command.gripper_force_n;
  sample.enable = command.enable;
}

void from_dds(const afhub_dds_DeviceCommand& sample, DeviceCommand& command) noexcept {
  from_dds(sample.header, command.header);
  command.wrench = from_dds(sample.wrench);
  command.gripper_force_n = sample.gripper_force_n;
  command.enable = sample.enable;  // the driver clamps the force whatever it says
}

void to_dds(std::string_view channel, const WorldState& state,
            afhub_dds_WorldState& sample) noexcept {
  copy_text(channel, sample.world);
  sample.header = to_dds(state.header);
  copy_world_values(state, sample);
  copy_text(state.last_nan_body.data(), state.last_nan_body.size(), sample.last_nan_body);
  poses_out(state.lights, state.light_count, sample.lights);
  poses_out(state.cameras, state.camera_count, sample.cameras);
}

void from_dds(const afhub_dds_WorldState& sample, WorldState& state) noexcept {
  from_dds(sample.header, state.header);
  copy_world_values(sample, state);
  state.step_due_ns = 0;  // the other machine's clock: no phase to keep here
  state.step_period_ns = 0;
  copy_text(sample.last_nan_body, state.last_nan_body);
  state.light_count = poses_in(sample.lights, state.lights);
  state.camera_count = poses_in(sample.cameras, state.cameras);
}

void to_dds(std::string_view channel, const WorldCommand& command,
            afhub_dds_WorldCommand& sample) noexcept {
  copy_text(channel, sample.world);
  sample.header = to_dds(command.header);
  sample.action = static_cast<std::uint32_t>(command.action);
  sample.step_count = command.step_count;
  sample.hold_ms = command.hold_ms;
  sample.valid_ms = command.valid_ms;
}

bool from_dds(const afhub_dds_WorldCommand& sample, WorldCommand& command) noexcept {
  if (sample.action > static_cast<std::uint32_t>(WorldAction::kRelease) ||
      sample.hold_ms > kMaxPauseHoldMs || sample.valid_ms > kMaxWorldCommandValidMs)
    return false;
  from_dds(sample.header, command.header);
  command.action = static_cast<WorldAction>(sample.action);
  command.step_count = sample.step_count;
  command.hold_ms = sample.hold_ms;
  command.valid_ms = sample.valid_ms;
  return true;
}

}  // namespace afhub::bridges
