#include "placed_copy.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <stdexcept>

namespace afhub::testing {

std::string placed_copy(const std::string& path, double dx, double dy, double dz) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& error) {
    throw std::runtime_error(path + ": cannot be read as YAML: " + error.what());
  }
  const std::filesystem::path folder = std::filesystem::absolute(path).parent_path();
  for (const char* key : {"high resolution path", "low resolution path"})
    if (YAML::Node mesh_folder = root[key]) {
      const std::filesystem::path written = mesh_folder.as<std::string>();
      if (written.is_relative()) root[key] = (folder / written).lexically_normal().string() + "/";
    }
  for (auto entry : root) {
    if (entry.first.as<std::string>().rfind("BODY ", 0) != 0) continue;
    YAML::Node position = entry.second["location"]["position"];
    if (!position) continue;
    position["x"] = position["x"].as<double>(0.0) + dx;
    position["y"] = position["y"].as<double>(0.0) + dy;
    position["z"] = position["z"].as<double>(0.0) + dz;
  }
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << root;
  return std::string(out.c_str()) + "\n";
}

}  // namespace afhub::testing
