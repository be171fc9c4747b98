// Loads URDF robots (parsed by liburdfdom) into the same Model an ADF file loads to:
// one body per link, channels "<robot>/<link>", one joint per URDF joint. Each
// body's frame is its URDF link frame (the pose tf and KDL report); each joint reads
// zero where the URDF puts zero. Problems are afhub::Error "file:line:col: error: ...".
#pragma once

#include <string>
#include <vector>

#include "afhub/physics/model.hpp"

namespace afhub::physics {

struct UrdfOptions {
  std::vector<std::string> package_paths;  // --package-path, searched before ROS_PACKAGE_PATH
  bool floating_base = false;              // the root link free (a root called `world` stays fixed)
};

// Whether `path` names a URDF (or a xacro file, which load_urdf_into refuses).
bool is_urdf_path(const std::string& path);

// Appends the robot's bodies and joints to `model` (its joints resolved), its
// warnings to model.warnings and what was chosen for it (the root) to model.notes.
// The caller computes the lineage and checks the whole model, as for ADF files.
void load_urdf_into(const std::string& path, const UrdfOptions& options, Model& model);

}  // namespace afhub::physics
