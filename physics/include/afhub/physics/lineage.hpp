// Lineage (AMBF paper, Algorithm 1): every body's descendant joints, and the
// number of closed kinematic loops.
#pragma once

#include <vector>

#include "afhub/physics/model.hpp"

namespace afhub::physics {

// Each body's joints, those whose parent it is, in the file's order.
std::vector<std::vector<int>> joints_by_parent(const Model& model);

// Fills model.descendant_joints and model.closed_loop_count from bodies and joints.
void compute_lineage(Model& model);

}  // namespace afhub::physics
