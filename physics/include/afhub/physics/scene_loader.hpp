// What `afhub run` loads, as ambf_simulator takes it: a launch file with indices
// into its `multibody configs` (-l 0,3), ADF files (-a a.yaml,b.yaml or plain
// arguments), and the world file named by the launch file or given directly.
#pragma once

#include <string>
#include <vector>

#include "afhub/physics/model.hpp"
#include "afhub/physics/urdf_loader.hpp"

namespace afhub::physics {

// Where to put a loaded file: every body of it moved rigidly by `placement`, about
// the world's origin (AMBF draws its robots at the origin, where they overlap). From
// `afhub run --at FILE=x,y,z[,r,p,y]`, or a launch file's `at:` map (an afhub key AMBF
// ignores: `at: {./robots/mtm.yaml: [3, 0, 0]}`). Of a file loaded several times, each
// placement names the next copy.
struct FilePlacement {
  std::string file;  // as given; must name one of the loaded files
  Placement placement;
};

struct SceneRequest {
  std::string launch_file;                // empty: none
  std::vector<int> launch_indices;        // into the launch file's `multibody configs`
  std::vector<std::string> adf_files;     // loaded after the launch file's models
  std::string world_file;                 // overrides the launch file's `world config`
  UrdfOptions urdf;                       // for URDF files among the models
  std::vector<FilePlacement> placements;  // after the launch file's `at:`
};

// Throws afhub::Error "file:line:col: error: ..." for any problem.
Model load_scene(const SceneRequest& request);

// Parses "FILE=x,y,z" or "FILE=x,y,z,r,p,y" (metres, radians: the --at option); throws
// afhub::Error naming --at on anything else.
FilePlacement parse_file_placement(const std::string& text);

// Parses "0,3,5" (the -l option); throws afhub::Error on anything else.
std::vector<int> parse_index_list(const std::string& text);

}  // namespace afhub::physics
