// Which parts of a model are open chains that can be simulated in reduced coordinates
// (WorldSpec::reduced_coordinates): a tree of moving bodies that hangs from a static
// body by exactly one joint, every joint of it revolute, continuous, prismatic or
// fixed, pointing from the static body outwards (each joint's parent nearer to it),
// with no joint error settings (erp, cfm) and no actuator on its bodies. Anything
// else (a closed loop, a free-floating robot, a spring, a gripper's actuator) stays in
// maximal coordinates, as without the option.
#pragma once

#include <vector>

#include "afhub/physics/model.hpp"

namespace afhub::physics {

struct ChainPlan {
  int base = -1;            // the static body
  std::vector<int> joints;  // per link, the joint that moves it, parents before children
  std::vector<int> parent;  // per link, its parent link; -1: the base
};

std::vector<ChainPlan> plan_chains(const Model& model);

}  // namespace afhub::physics
