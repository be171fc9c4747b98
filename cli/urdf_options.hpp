// `--package-path DIR` and `--floating-base`, for `afhub run`, `check` and `convert`:
// how URDF files among the models load (physics/urdf_loader.hpp).
#pragma once

#include <CLI/CLI.hpp>

#include "afhub/physics/urdf_loader.hpp"

namespace afhub::cli {

inline void add_urdf_options(CLI::App* command, physics::UrdfOptions& options) {
  command->add_option("--package-path", options.package_paths,
                      "URDF: a folder holding the packages `package://NAME/...` mesh URIs name "
                      "(repeatable); searched before ROS_PACKAGE_PATH and the URDF's own folders");
  command->add_flag("--floating-base", options.floating_base,
                    "URDF: leave the root link free (legged and flying robots) instead of fixed "
                    "to the world; a root link called `world` stays fixed");
}

}  // namespace afhub::cli
