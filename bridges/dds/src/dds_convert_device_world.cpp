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
  sample.spec.max_force_n = state.spec.max_force_n;
  sample.spec.max_torque_nm = state.spec.max_torque_nm;
  sample.spec.max_gripper_force_n = state.spec.max_gripper_force_n;
  sample.spec.max_stiffness_npm = state.spec.max_stiffness_npm;
  sample.spec.workspace_radius_m = state.spec.workspace_radius_m;
  sample.spec.sensed = state.spec.sensed;
  sample.spec.actuated = state.spec.actuated;
  sample.spec.button_count = state.spec.button_count;
  sample.pose = to_dds(state.pose);
  sample.velocity = to_dds(state.velocity);
  sample.gripper_angle_rad = state.gripper_angle_rad;
  sample.buttons = state.buttons;
  sample.gate = static_cast<std::uint8_t>(state.gate);
  sample.applied = to_dds(state.applied);
  sample.applied_gripper_force_n = state.applied_gripper_force_n;
  sample.command_sequence = state.command_sequence;
  sample.command_stamp_ns = state.command_stamp_ns;
}

bool from_dds(const afhub_dds_DeviceState& sample, DeviceState& state) noexcept {
  if (sample.gate > static_cast<std::uint8_t>(ForceGate::kStopping)) return false;
  from_dds(sample.header, state.header);
  copy_text(sample.spec.model, state.spec.model);
  copy_text(sample.spec.serial, state.spec.serial);
  state.spec.max_force_n = sample.spec.max_force_n;
  state.spec.max_torque_nm = sample.spec.max_torque_nm;
  state.spec.max_gripper_force_n = sample.spec.max_gripper_force_n;
  state.spec.max_stiffness_npm = sample.spec.max_stiffness_npm;
  state.spec.workspace_radius_m = sample.spec.workspace_radius_m;
  state.spec.sensed = sample.spec.sensed;
  state.spec.actuated = sample.spec.actuated;
  state.spec.button_count = sample.spec.button_count;
  state.pose = from_dds(sample.pose);
  state.velocity = from_dds(sample.velocity);
  state.gripper_angle_rad = sample.gripper_angle_rad;
  state.buttons = sample.buttons;
  state.gate = static_cast<ForceGate>(sample.gate);
  state.applied = from_dds(sample.applied);
  state.applied_gripper_force_n = sample.applied_gripper_force_n;
  state.command_sequence = sample.command_sequence;
  state.command_stamp_ns = sample.command_stamp_ns;
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
  sample.wall_time_s = state.wall_time_s;
  sample.achieved_rate_hz = state.achieved_rate_hz;
  sample.body_count = state.body_count;
  sample.paused = state.paused;
  sample.lockstep = state.lockstep;
  sample.rejected_commands = state.rejected_commands;
  sample.watchdog_expiries = state.watchdog_expiries;
  sample.stale_commands = state.stale_commands;
  sample.lockstep_clients = state.lockstep_clients;
  sample.late_answers = state.late_answers;
  sample.dropped_clients = state.dropped_clients;
  sample.commanded_steps = state.commanded_steps;
  sample.answered_steps = state.answered_steps;
  sample.nan_recoveries = state.nan_recoveries;
  sample.last_nan_step = state.last_nan_step;
  copy_text(state.last_nan_body.data(), state.last_nan_body.size(), sample.last_nan_body);
  poses_out(state.lights, state.light_count, sample.lights);
  poses_out(state.cameras, state.camera_count, sample.cameras);
}

void from_dds(const afhub_dds_WorldState& sample, WorldState& state) noexcept {
  from_dds(sample.header, state.header);
  state.wall_time_s = sample.wall_time_s;
  state.achieved_rate_hz = sample.achieved_rate_hz;
  state.body_count = sample.body_count;
  state.paused = sample.paused;
  state.lockstep = sample.lockstep;
  state.rejected_commands = sample.rejected_commands;
  state.watchdog_expiries = sample.watchdog_expiries;
  state.stale_commands = sample.stale_commands;
  state.lockstep_clients = sample.lockstep_clients;
  state.late_answers = sample.late_answers;
  state.dropped_clients = sample.dropped_clients;
  state.commanded_steps = sample.commanded_steps;
  state.answered_steps = sample.answered_steps;
  state.nan_recoveries = sample.nan_recoveries;
  state.last_nan_step = sample.last_nan_step;
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
}

bool from_dds(const afhub_dds_WorldCommand& sample, WorldCommand& command) noexcept {
  if (sample.action > static_cast<std::uint32_t>(WorldAction::kReset)) return false;
  from_dds(sample.header, command.header);
  command.action = static_cast<WorldAction>(sample.action);
  command.step_count = sample.step_count;
  return true;
}

}  // namespace afhub::bridges
