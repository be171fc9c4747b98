// What `afhub run` loads, as ambf_simulator takes it: a launch file with indices
// into its `multibody configs` (-l 0,3), ADF files (-a a.yaml,b.yaml or plain
// arguments), and the world file named by the launch file or given directly.
#pragma once

#include <string>
#include <vector>

#include "afhub/physics/model.hpp"
#include "afhub/physics/urdf_loader.hpp"

namespace afhub::physics {

struct SceneRequest {
  std::string launch_file;             // empty: none
  std::vector<int> launch_indices;     // into the launch file's `multibody configs`
  std::vector<std::string> adf_files;  // loaded after the launch file's models
  std::string world_file;              // overrides the launch file's `world config`
  UrdfOptions urdf;                    // for URDF files among the models
};

// Throws afhub::Error "file:line:col: error: ..." for any problem.
Model load_scene(const SceneRequest& request);

// Parses "0,3,5" (the -l option); throws afhub::Error on anything else.
std::vector<int> parse_index_list(const std::string& text);

}  // namespace afhub::physics
