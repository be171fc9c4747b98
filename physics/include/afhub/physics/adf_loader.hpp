// Loads AMBF description files (ADF 1.0) into a Model. Every problem is an
// afhub::Error whose message reads "file:line:col: error: <what and how to fix it>".
#pragma once

#include <string>
#include <vector>

#include "afhub/physics/model.hpp"

namespace afhub::physics {

// Loads the files together: joints may refer to bodies of any of them.
Model load_adf_files(const std::vector<std::string>& paths);

// The same into `model`, which keeps its world settings (see scene_loader.hpp).
void load_adf_files_into(const std::vector<std::string>& paths, Model& model);

}  // namespace afhub::physics
