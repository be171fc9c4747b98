// DeviceState, DeviceCommand, WorldState and WorldCommand to and from afhub's DDS
// types, every field. As in dds_convert.hpp: samples own full-capacity buffers
// (make_world_state_sample), so conversions never allocate; from_dds copies a
// header's sim step and time, the hub's writer stamps the rest on publish; and a
// value from the network that no afhub writer makes is refused (false).
#pragma once

#include <string_view>

#include "afhub/shm_layout/device.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub_dds.h"

namespace afhub::bridges {

void make_world_state_sample(afhub_dds_WorldState& sample);
void free_world_state_sample(afhub_dds_WorldState& sample);

void to_dds(std::string_view channel, const DeviceState& state,
            afhub_dds_DeviceState& sample) noexcept;
void to_dds(std::string_view channel, const DeviceCommand& command,
            afhub_dds_DeviceCommand& sample) noexcept;
void to_dds(std::string_view channel, const WorldState& state,
            afhub_dds_WorldState& sample) noexcept;
void to_dds(std::string_view channel, const WorldCommand& command,
            afhub_dds_WorldCommand& sample) noexcept;

bool from_dds(const afhub_dds_DeviceState& sample, DeviceState& state) noexcept;
void from_dds(const afhub_dds_DeviceCommand& sample, DeviceCommand& command) noexcept;
void from_dds(const afhub_dds_WorldState& sample, WorldState& state) noexcept;
bool from_dds(const afhub_dds_WorldCommand& sample, WorldCommand& command) noexcept;

}  // namespace afhub::bridges
