// Writes a Model's rigid bodies and joints as an ADF 1.0 file (`afhub convert`): the
// file `afhub run` loads to the same bodies, joints and poses. Meshes are written as
// absolute paths; numbers with 17 significant digits, so they read back exactly.
#pragma once

#include <string>
#include <vector>

#include "afhub/physics/model.hpp"

namespace afhub::physics {

// The ADF text; `lost` gets one line per thing ADF cannot say (a mimic joint).
std::string adf_text(const Model& model, std::vector<std::string>& lost);

}  // namespace afhub::physics
