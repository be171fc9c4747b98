// What `afhub run` and `afhub check` load, given the same way to both: model files,
// a launch file and its picks, -a lists, a world file, placements and URDF options,
// so that `check` takes every scene `run` takes.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "afhub/physics/scene_loader.hpp"

namespace afhub::cli {

struct SceneOptions {
  std::vector<std::string> files;
  std::string launch_file, world_file;
  std::vector<std::string> indices;     // each "0,3"; -l repeated adds to them
  std::vector<std::string> adf_lists;   // each "a.yaml,b.yaml"
  std::vector<std::string> placements;  // "FILE=x,y,z[,r,p,y]"
  physics::UrdfOptions urdf;
};

// `world_help` says what the command takes of a world file.
void add_scene_options(CLI::App* command, SceneOptions& options, const std::string& world_help);

// The scene to load; throws afhub::Error on a malformed -l or --at.
physics::SceneRequest scene_request(const SceneOptions& options);

}  // namespace afhub::cli
