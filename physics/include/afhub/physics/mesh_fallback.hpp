// `afhub run --mesh-fallback box`: a body whose collision mesh cannot be used (the
// reader crashed or timed out on it, it is corrupt, it has no triangles) collides as a
// box instead of the model being refused.
#pragma once

#include <string>
#include <vector>

#include "afhub/physics/model.hpp"

namespace afhub::physics {

// Reads every body's collision meshes; each body with a mesh that cannot be used
// collides as a box instead of its meshes (beside its primitive shapes), made from
// what its block does say: with a mass and an `inertia`, the solid box of that mass
// whose principal inertias are those, turned and placed as its `inertial offset`;
// else a 10 cm cube there. Returns a warning for each: "FILE:LINE:COL: warning: body
// 'X': its mesh cannot be used (WHY): ...". The meshes read stay kept for the
// simulation's build (mesh.hpp).
std::vector<std::string> fall_back_to_boxes(Model& model);

}  // namespace afhub::physics
