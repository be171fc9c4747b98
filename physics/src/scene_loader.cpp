// Launch and world files (see scene_loader.hpp). The world file sets gravity,
// solver iterations, the enclosure, lights and cameras, and names an environment
// ADF; the launch file names the world, colors, input devices and the models.
#include "afhub/physics/scene_loader.hpp"

#include <charconv>
#include <filesystem>
#include <map>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "file_reader.hpp"
#include "path_kind.hpp"

namespace afhub::physics {
namespace {

namespace fs = std::filesystem;

// A path written in `file` at `node`, relative to that file's folder; must exist.
std::string existing_path(const FileReader& file, const YAML::Node& node, const std::string& what) {
  const fs::path written(file.text(node, what));
  const fs::path resolved =
      written.is_absolute() ? written : fs::path(file.path()).parent_path() / written;
  if (const std::string why = not_a_regular_file(resolved); !why.empty())
    fail(file.at(node), what + " '" + written.string() +
                            "': " + resolved.lexically_normal().string() + " " + why +
                            "; fix the path, relative to this file");
  return resolved.lexically_normal().string();
}

WorldObjectSpec read_world_object(const FileReader& file, const YAML::Node& block,
                                  const std::string& identifier, const std::string& name_space,
                                  bool camera) {
  WorldObjectSpec object;
  file.require_map(block, identifier, "{name: light1, location: {x, y, z}}");
  std::string ns = name_space;
  if (YAML::Node given = block["namespace"])
    ns = resolve_namespace(name_space, file.text(given, "namespace"));
  const std::string name = block["name"] ? file.text(block["name"], "name") : identifier;
  object.key = identifier;
  object.name = body_channel_name(ns, name);
  if (YAML::Node location = block["location"])
    object.position_m = file.position(location, "location");
  if (camera) {
    Vec3 look_at;
    if (YAML::Node target = block["look at"]) look_at = file.position(target, "look at");
    object.direction = {look_at.x - object.position_m.x, look_at.y - object.position_m.y,
                        look_at.z - object.position_m.z};
    if (YAML::Node up = block["up"]) object.up = file.axis(up, "up");
  } else {
    object.direction = {0.0, 0.0, -1.0};
    if (YAML::Node direction = block["direction"])
      object.direction = file.axis(direction, "direction");
  }
  if (YAML::Node parent = block["parent"]) object.parent = file.text(parent, "parent");
  return object;
}

// Reads the world file into model.world; returns its environment ADF, if any.
std::string load_world(const std::string& path, Model& model) {
  const YAML::Node root = yaml::load_map(path, "a world file (enclosure, lights, cameras, ...)");
  FileReader file(path, model);
  WorldSpec& world = model.world;
  world.file = path;
  std::string name_space = "/ambf/env/";
  if (YAML::Node ns = root["namespace"])
    name_space = resolve_namespace(name_space, file.text(ns, "namespace"));
  if (YAML::Node gravity = root["gravity"]) world.gravity_mps2 = file.vec3(gravity, "gravity");
  if (YAML::Node enclosure = root["enclosure size"])
    world.enclosure_m = file.vec3(enclosure, "enclosure size", "length", "width", "height");
  if (YAML::Node iterations = root["max iterations"]) {
    const double value = file.number(iterations, "max iterations");
    if (value < 1 || value > 1000 || value != static_cast<int>(value))
      fail(file.at(iterations), "'max iterations' must be an integer from 1 to 1000");
    world.max_iterations = static_cast<int>(value);
  }
  const yaml::MapIndex index(file, root);
  for (const char* kind : {"lights", "cameras"}) {
    const bool camera = std::string(kind) == "cameras";
    auto& objects = camera ? world.cameras : world.lights;
    for (const auto& [identifier, listed, block] : header_list(file, index, kind)) {
      // The world state carries a fixed number of each (shm_layout/limits.hpp).
      if (objects.size() == kMaxWorldObjects)
        fail(file.at(listed), "more than " + std::to_string(kMaxWorldObjects) + " " + kind +
                                  ": the world state carries at most " +
                                  std::to_string(kMaxWorldObjects) + "; remove '" + identifier +
                                  "' or others");
      objects.push_back(read_world_object(file, block, identifier, name_space, camera));
    }
  }
  if (YAML::Node environment = root["environment"])
    return existing_path(file, environment, "environment");
  return {};
}

// Named colors (r, g, b, a from 0 to 255) for bodies that say `color: <name>`.
void apply_colors(const std::string& path, Model& model) {
  const YAML::Node root = yaml::load_map(path, "a color file (name: {r, g, b, a})");
  FileReader file(path, model);
  const yaml::MapIndex index(file, root);
  for (BodySpec& body : model.bodies) {
    if (body.color_name.empty() || body.color_rgba) continue;
    const YAML::Node* found = index.find(body.color_name);
    if (!found) continue;  // "random" and unknown names: the viewer's choice
    const YAML::Node& color = *found;
    const Vec3 rgb = file.vec3(color, body.color_name, "r", "g", "b");
    const double alpha = color["a"] ? file.number(color["a"], body.color_name + ".a") : 255.0;
    body.color_rgba = std::array<double, 4>{rgb.x / 255, rgb.y / 255, rgb.z / 255, alpha / 255};
  }
}

}  // namespace

std::vector<int> parse_index_list(const std::string& text) {
  std::vector<int> indices;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    int value = -1;
    const char* first = text.data() + start;
    const char* last = text.data() + end;
    auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec != std::errc() || ptr != last || value < 0)
      throw Error("'" + text + "' is not a list of model indices such as 0,3,5");
    indices.push_back(value);
    start = end + 1;
  }
  return indices;
}

Model load_scene(const SceneRequest& request) {
  Model model;
  std::vector<std::string> adf_files;
  std::string world_file = request.world_file, color_file;
  if (!request.launch_file.empty()) {
    const YAML::Node root =
        yaml::load_map(request.launch_file, "a launch file ('world config', 'multibody configs')");
    FileReader file(request.launch_file, model);
    if (YAML::Node world = root["world config"]; world && world_file.empty())
      world_file = existing_path(file, world, "world config");
    if (YAML::Node colors = root["color config"])
      color_file = existing_path(file, colors, "color config");
    if (YAML::Node devices = root["input devices config"])
      existing_path(file, devices, "input devices config");  // used by the device drivers
    const YAML::Node configs = root["multibody configs"];
    if (configs && !configs.IsSequence())
      fail(file.at(configs), "'multibody configs' must be a list of ADF paths");
    const int count = configs ? static_cast<int>(configs.size()) : 0;
    // A launch file alone would load its world and nothing else: say what there is to pick.
    if (request.launch_indices.empty() && request.adf_files.empty() && count > 0) {
      std::string listed;
      for (int index = 0; index < count; ++index)
        listed += "\n  " + std::to_string(index) + ": " +
                  (configs[index].IsScalar() ? configs[index].Scalar() : std::string("?"));
      fail(file.at(configs),
           "no model picked from 'multibody configs': give -l with their indices, "
           "e.g. -l 0 or -l 0,2; the configs are:" +
               listed);
    }
    for (int index : request.launch_indices) {
      if (index >= count)
        fail(file.at(configs ? configs : root), "model index " + std::to_string(index) +
                                                    " (-l) is beyond 'multibody configs', which "
                                                    "has " +
                                                    std::to_string(count) + " entries (0 to " +
                                                    std::to_string(count - 1) + ")");
      adf_files.push_back(
          existing_path(file, configs[index], "multibody config #" + std::to_string(index)));
    }
  } else if (!request.launch_indices.empty()) {
    throw Error("-l picks models from a launch file; give one with --launch FILE");
  }
  std::string environment;
  if (!world_file.empty()) environment = load_world(world_file, model);
  if (!environment.empty()) adf_files.insert(adf_files.begin(), environment);
  adf_files.insert(adf_files.end(), request.adf_files.begin(), request.adf_files.end());
  if (adf_files.empty())
    throw Error("nothing to simulate: give ADF files, or --launch FILE with -l indices");
  load_adf_files_into(adf_files, model, request.urdf);
  if (!color_file.empty()) apply_colors(color_file, model);
  return model;
}

}  // namespace afhub::physics
