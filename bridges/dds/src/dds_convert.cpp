// BodyState and BodyCommand to and from afhub's DDS types (see dds_convert.hpp).
#include "dds_convert.hpp"

#include <algorithm>

#include "dds_convert_parts.hpp"

namespace afhub::bridges {

// Layouts agree, so vectors copy field by field with no surprises.
static_assert(sizeof(afhub_dds_JointSample) == sizeof(JointSample));

void make_state_sample(afhub_dds_BodyState& sample) {
  sample = {};
  reserve(sample.sensor_distances_m, kMaxSensorRaysPerBody);
  reserve(sample.joints, kMaxJointsPerBody);
}

void make_command_sample(afhub_dds_BodyCommand& sample) {
  sample = {};
  reserve(sample.actuate, kMaxActuatorsPerBody);
  reserve(sample.joints, kMaxJointsPerBody);
}

void free_state_sample(afhub_dds_BodyState& sample) {
  dds_sample_free(&sample, &afhub_dds_BodyState_desc, DDS_FREE_CONTENTS);
}

void free_command_sample(afhub_dds_BodyCommand& sample) {
  dds_sample_free(&sample, &afhub_dds_BodyCommand_desc, DDS_FREE_CONTENTS);
}

void to_dds(std::string_view channel, const BodyState& state,
            afhub_dds_BodyState& sample) noexcept {
  copy_text(channel, sample.body);
  sample.header = to_dds(state.header);
  sample.pose = to_dds(state.pose);
  sample.twist = to_dds(state.twist);
  sample.wrench = to_dds(state.wrench);
  sample.contact_wrench = to_dds(state.contact_wrench);
  sample.mass_kg = state.mass_kg;
  sample.principal_inertia_kgm2 = to_dds(state.principal_inertia_kgm2);
  sample.commanded_steps = state.commanded_steps;
  sample.answered_steps = state.answered_steps;
  sample.command_answered_step = state.command_answered_step;
  sample.contact_count = state.contact_count;
  const std::uint32_t rays = std::min<std::uint32_t>(state.sensor_ray_count, kMaxSensorRaysPerBody);
  std::copy_n(state.sensor_distances_m.data(), rays, sample.sensor_distances_m._buffer);
  sample.sensor_distances_m._length = rays;
  const std::uint32_t joints = std::min<std::uint32_t>(state.joint_count, kMaxJointsPerBody);
  for (std::uint32_t j = 0; j < joints; ++j)
    sample.joints._buffer[j] = {state.joints[j].position, state.joints[j].velocity,
                                state.joints[j].effort};
  sample.joints._length = joints;
}

void to_dds(std::string_view channel, const BodyCommand& command,
            afhub_dds_BodyCommand& sample) noexcept {
  copy_text(channel, sample.body);
  sample.header = to_dds(command.header);
  sample.cartesian_type = static_cast<std::uint8_t>(command.cartesian_type);
  sample.lockstep = command.lockstep;
  sample.pose = to_dds(command.pose);
  sample.wrench = to_dds(command.wrench);
  sample.twist = to_dds(command.twist);
  const std::uint32_t actuators =
      std::min<std::uint32_t>(command.actuator_count, kMaxActuatorsPerBody);
  std::copy_n(command.actuate.data(), actuators, sample.actuate._buffer);
  sample.actuate._length = actuators;
  const std::uint32_t joints = std::min<std::uint32_t>(command.joint_count, kMaxJointsPerBody);
  for (std::uint32_t j = 0; j < joints; ++j)
    sample.joints._buffer[j] = {command.joints[j].value,
                                static_cast<std::uint8_t>(command.joints[j].type)};
  sample.joints._length = joints;
}

void from_dds(const afhub_dds_BodyState& sample, BodyState& state) noexcept {
  from_dds(sample.header, state.header);
  state.pose = from_dds(sample.pose);
  state.twist = from_dds(sample.twist);
  state.wrench = from_dds(sample.wrench);
  state.contact_wrench = from_dds(sample.contact_wrench);
  state.mass_kg = sample.mass_kg;
  state.principal_inertia_kgm2 = from_dds(sample.principal_inertia_kgm2);
  state.step_due_ns = 0;  // a due time on the other machine's clock means nothing here
  state.commanded_steps = sample.commanded_steps;
  state.answered_steps = sample.answered_steps;
  state.command_answered_step = sample.command_answered_step;
  state.contact_count = sample.contact_count;
  state.sensor_ray_count =
      std::min<std::uint32_t>(sample.sensor_distances_m._length, kMaxSensorRaysPerBody);
  std::copy_n(sample.sensor_distances_m._buffer, state.sensor_ray_count,
              state.sensor_distances_m.data());
  state.joint_count = std::min(state.joint_count, sample.joints._length);
  for (std::uint32_t j = 0; j < state.joint_count; ++j)
    state.joints[j] = {sample.joints._buffer[j].position, sample.joints._buffer[j].velocity,
                       sample.joints._buffer[j].effort};
}

bool valid_dds_command(const afhub_dds_BodyCommand& sample) noexcept {
  if (sample.cartesian_type > 2 || sample.actuate._length > kMaxActuatorsPerBody) return false;
  for (std::uint32_t j = 0; j < sample.joints._length; ++j)
    if (sample.joints._buffer[j].type > 2) return false;
  return true;
}

bool from_dds(const afhub_dds_BodyCommand& sample, BodyCommand& command) noexcept {
  if (!valid_dds_command(sample)) return false;
  from_dds(sample.header, command.header);
  command.cartesian_type = static_cast<CartesianCommandType>(sample.cartesian_type);
  command.lockstep = sample.lockstep;
  command.pose = from_dds(sample.pose);
  command.wrench = from_dds(sample.wrench);
  command.twist = from_dds(sample.twist);
  command.actuator_count = sample.actuate._length;
  std::copy_n(sample.actuate._buffer, command.actuator_count, command.actuate.data());
  command.joint_count = std::min(command.joint_count, sample.joints._length);
  for (std::uint32_t j = 0; j < command.joint_count; ++j)
    command.joints[j] = {sample.joints._buffer[j].value,
                         static_cast<JointCommandType>(sample.joints._buffer[j].type),
                         {}};
  return true;
}

}  // namespace afhub::bridges
