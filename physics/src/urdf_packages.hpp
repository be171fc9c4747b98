// Where a URDF's mesh URIs point: `package://NAME/rest`, `file:///abs/path`, or a
// path relative to the URDF's folder. Internal to the URDF loader.
#pragma once

#include <string>
#include <vector>

namespace afhub::physics::urdf_files {

// The file `uri` names, for a URDF in `urdf_dir`. A package is looked for in each of
// `package_paths` (`--package-path`), then in ROS_PACKAGE_PATH's folders, then in the
// URDF's folder and each folder above it: a folder is package NAME when its
// package.xml names NAME or it is called NAME, and a folder holding such a folder
// counts too. Returns the path, or empty with `looked` saying where it looked.
std::string resolve_uri(const std::string& uri, const std::string& urdf_dir,
                        const std::vector<std::string>& package_paths, std::string& looked);

// Whether `uri` is a package:// path that climbs out of its package
// ("package://arm/../../etc/passwd", "package://arm//etc/passwd", "package://../x"): it
// names no file of that package.
bool leaves_its_package(const std::string& uri);

}  // namespace afhub::physics::urdf_files
