// Loads AMBF description files (ADF 1.0) into a Model. Every problem is an
// afhub::Error whose message reads "file:line:col: error: <what and how to fix it>".
#pragma once

#include <string>
#include <vector>

#include "afhub/physics/model.hpp"
#include "afhub/physics/urdf_loader.hpp"

namespace afhub::physics {

// Loads the files together: joints may refer to bodies of any of them.
Model load_adf_files(const std::vector<std::string>& paths);

// The same into `model`, which keeps its world settings (see scene_loader.hpp). URDF
// files among `paths` (is_urdf_path) load through urdf_loader.hpp with `urdf`; ADF
// joints may join their links ("BODY <link>").
void load_adf_files_into(const std::vector<std::string>& paths, Model& model,
                         const UrdfOptions& urdf = {});

}  // namespace afhub::physics
