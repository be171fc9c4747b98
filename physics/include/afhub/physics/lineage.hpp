// Lineage (AMBF paper, Algorithm 1): every body's descendant joints, and the
// number of closed kinematic loops.
#pragma once

#include "afhub/physics/model.hpp"

namespace afhub::physics {

// Fills model.descendant_joints and model.closed_loop_count from bodies and joints.
void compute_lineage(Model& model);

}  // namespace afhub::physics
