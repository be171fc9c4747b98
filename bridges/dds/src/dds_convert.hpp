// BodyState and BodyCommand to and from afhub's DDS types. The DDS samples own
// buffers of the full capacity (make_*), so conversions never allocate.
#pragma once

#include <string_view>

#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub_dds.h"

namespace afhub::bridges {

// Samples whose sequences hold the full capacity (kMaxJointsPerBody...), for writing
// and for dds_take to deserialize into without reallocating; free with free_sample.
void make_state_sample(afhub_dds_BodyState& sample);
void make_command_sample(afhub_dds_BodyCommand& sample);
void free_state_sample(afhub_dds_BodyState& sample);
void free_command_sample(afhub_dds_BodyCommand& sample);

void to_dds(std::string_view channel, const BodyState& state, afhub_dds_BodyState& sample) noexcept;
void to_dds(std::string_view channel, const BodyCommand& command,
            afhub_dds_BodyCommand& sample) noexcept;
// Into a loaned state or command holding `joints` joints: at most that many are
// copied (joint_count set accordingly). The header's sim step and time are copied;
// the hub's writer stamps the rest on publish.
void from_dds(const afhub_dds_BodyState& sample, BodyState& state) noexcept;
// False when a type or count is out of range: a network command is untrusted.
// Checked before loaning, so that a refused command holds no chunk.
bool valid_dds_command(const afhub_dds_BodyCommand& sample) noexcept;
// False (command untouched) when !valid_dds_command(sample).
bool from_dds(const afhub_dds_BodyCommand& sample, BodyCommand& command) noexcept;

}  // namespace afhub::bridges
