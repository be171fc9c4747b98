// Where two body states of one step differ, in what the physics computes (pose, twist,
// wrenches, joints, sensor distances, the contact count), bit for bit; clocks, counters
// and senders are left out.
#pragma once

#include <string>

#include "afhub/shm_layout/body_state.hpp"

namespace afhub::mcap {

// "" when they agree; else the first field that differs, with both values.
std::string state_difference(const BodyState& recorded, const BodyState& replayed);

}  // namespace afhub::mcap
