// Launch and world files (see scene_loader.hpp). The world file sets gravity,
// solver iterations, the enclosure, lights and cameras, and names an environment
// ADF; the launch file names the world, colors, input devices and the models.
#include "afhub/physics/scene_loader.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "file_reader.hpp"
#include "frames.hpp"
#include "path_kind.hpp"

namespace afhub::physics {
namespace {

namespace fs = std::filesystem;

// A path written in `file` at `node`, relative to that file's folder.
fs::path resolved_path(const FileReader& file, const YAML::Node& node, const std::string& what) {
  const fs::path written(file.text(node, what));
  return written.is_absolute() ? written : fs::path(file.path()).parent_path() / written;
}

// The same, which must exist.
std::string existing_path(const FileReader& file, const YAML::Node& node, const std::string& what) {
  const fs::path written(file.text(node, what));
  const fs::path resolved = resolved_path(file, node, what);
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
    const double reach = std::hypot(object.direction.x, object.direction.y, object.direction.z);
    if (reach < 1e-9)
      fail(file.at(block["look at"] ? block["look at"] : block),
           "camera '" + identifier +
               "' looks at its own location: give it a 'look at' "
               "elsewhere");
    if (YAML::Node up = block["up"]) {
      object.up = file.axis(up, "up");
      const Vec3& d = object.direction;
      const Vec3& u = object.up;
      const double cross =
          std::hypot(d.y * u.z - d.z * u.y, d.z * u.x - d.x * u.z, d.x * u.y - d.y * u.x);
      if (cross < 1e-6 * reach * std::hypot(u.x, u.y, u.z))
        fail(file.at(up), "camera '" + identifier +
                              "': 'up' is along the direction it looks, so its image has no "
                              "up; give an 'up' across the view");
    }
  } else {
    object.direction = {0.0, 0.0, -1.0};
    if (YAML::Node direction = block["direction"])
      object.direction = file.axis(direction, "direction");
  }
  if (YAML::Node parent = block["parent"]) {
    object.parent = file.text(parent, "parent");
    object.parent_at = file.at(parent);
  }
  return object;
}

// A light or camera whose parent names no body loaded stays in the world frame, as in
// AMBF: said, since it was meant to move with that body.
void warn_parents_not_loaded(Model& model) {
  for (const auto* objects : {&model.world.lights, &model.world.cameras})
    for (const WorldObjectSpec& object : *objects) {
      if (!object.parent.empty() && world_object_parent(model, object) < 0)
        model.warnings.push_back(object.parent_at.str() + ": warning: '" + object.key +
                                 "' has the parent '" + object.parent +
                                 "', which names no body loaded; it stays where the world "
                                 "file puts it, in the world frame");
    }
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
  if (YAML::Node gravity = root["gravity"]) world.gravity_mps2 = file.gravity(gravity);
  if (YAML::Node enclosure = root["enclosure size"])
    world.enclosure_m = file.vec3(enclosure, "enclosure size", "length", "width", "height");
  if (YAML::Node iterations = root["max iterations"]) {
    const double value = file.number(iterations, "max iterations");
    if (value < 1 || value > 1000 || value != static_cast<int>(value))
      fail(file.at(iterations), "'max iterations' must be an integer from 1 to 1000");
    world.max_iterations = static_cast<int>(value);
  }
  // A model or a launch file given as the world would load nothing of it, silently.
  for (const char* key : {"bodies", "joints", "soft bodies", "sensors", "actuators"})
    if (YAML::Node node = root[key])
      file.warn(node, "'" + std::string(key) +
                          "' is a model file's key: a world file's models are not loaded. Give "
                          "this file as a model, or name it as the world's 'environment'");
  for (const char* key : {"world config", "multibody configs"})
    if (YAML::Node node = root[key])
      file.warn(node, "'" + std::string(key) +
                          "' is a launch file's key: this world file is not read as one; give "
                          "a launch file with --launch");
  const yaml::MapIndex index(file, root);
  for (const char* kind : {"lights", "cameras"}) {
    const bool camera = std::string(kind) == "cameras";
    auto& objects = camera ? world.cameras : world.lights;
    for (const auto& [identifier, listed, block] : header_list(file, index, kind)) {
      for (const WorldObjectSpec& earlier : objects)
        if (earlier.key == identifier)
          fail(file.at(listed), "'" + identifier + "' is listed twice in '" + kind + "'");
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

// The launch file's `at:` map, {config path: [x, y, z] or [x, y, z, r, p, y]}: each
// key resolved against the launch file and listed in its `multibody configs`.
std::vector<FilePlacement> read_launch_placements(const FileReader& file, const YAML::Node& at,
                                                  const std::vector<std::string>& configs) {
  if (!at.IsMap())
    fail(file.at(at),
         "'at' must map model paths of 'multibody configs' to [x, y, z] or "
         "[x, y, z, r, p, y] (metres, radians)");
  std::vector<FilePlacement> placements;
  for (const auto& entry : at) {
    const std::string path = resolved_path(file, entry.first, "'at' model").lexically_normal();
    if (std::find(configs.begin(), configs.end(), path) == configs.end())
      fail(file.at(entry.first), "'at' names '" + file.text(entry.first, "'at' model") +
                                     "', which is not in 'multibody configs'");
    const YAML::Node& value = entry.second;
    if (!value.IsSequence() || (value.size() != 3 && value.size() != 6))
      fail(file.at(value), "'at' takes [x, y, z] or [x, y, z, r, p, y] (metres, radians) for " +
                               file.text(entry.first, "'at' model"));
    double numbers[6] = {};
    for (std::size_t i = 0; i < value.size(); ++i)
      numbers[i] = i < 3 ? file.length(value[i], "at") : file.number(value[i], "at");
    placements.push_back(
        {path, {{numbers[0], numbers[1], numbers[2]}, {numbers[3], numbers[4], numbers[5]}}});
  }
  return placements;
}

// Moves every body and soft body of the loaded file `files[index]` by `placement`.
void place_file(Model& model, const std::vector<std::string>& files, std::size_t index,
                const Placement& placement) {
  const btTransform move = to_transform(placement);
  auto moved = [&](Placement& location) {
    const btTransform pose = move * to_transform(location);
    location = {from_bt(pose.getOrigin()), rpy_of(pose.getBasis())};
  };
  for (BodySpec& body : model.bodies)
    if (body.file_index == static_cast<int>(index)) moved(body.location);
  std::error_code error;
  for (SoftBodySpec& soft : model.soft_bodies)
    if (fs::equivalent(soft.where.file, files[index], error)) moved(soft.location);
}

// The loaded file that `placement` names, by path (any spelling of it): of a file
// loaded several times, the first copy not yet `placed`.
std::size_t placed_file(const std::vector<std::string>& files, const FilePlacement& placement,
                        std::vector<bool>& placed) {
  std::error_code error;
  bool loaded = false;
  for (std::size_t i = 0; i < files.size(); ++i)
    if (fs::equivalent(files[i], placement.file, error)) {
      loaded = true;
      if (!placed[i]) {
        placed[i] = true;
        return i;
      }
    }
  if (loaded)
    throw Error("--at names '" + placement.file +
                "' more times than it is loaded: each --at places one copy");
  std::string listed;
  for (const std::string& file : files) listed += "\n  " + file;
  throw Error("--at names '" + placement.file +
              "', which is not a loaded file; give one of the files loaded:" + listed);
}

}  // namespace

FilePlacement parse_file_placement(const std::string& text) {
  const std::string usage =
      "--at takes FILE=x,y,z or FILE=x,y,z,r,p,y (metres, radians), e.g. "
      "--at robots/mtm.yaml=3,0,0; got '" +
      text + "'";
  const std::size_t equals = text.rfind('=');
  if (equals == std::string::npos || equals == 0) throw Error(usage);
  std::vector<double> numbers;
  std::size_t start = equals + 1;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    double value = 0.0;
    auto [ptr, ec] = std::from_chars(text.data() + start, text.data() + end, value);
    if (ec != std::errc() || ptr != text.data() + end || !std::isfinite(value)) throw Error(usage);
    if (numbers.size() < 3 && std::abs(value) > kMaxLengthM)
      throw Error(usage + ": a position is at most " + yaml::number_text(kMaxLengthM) + " m");
    numbers.push_back(value);
    start = end + 1;
  }
  if (numbers.size() != 3 && numbers.size() != 6) throw Error(usage);
  numbers.resize(6, 0.0);
  return {text.substr(0, equals),
          {{numbers[0], numbers[1], numbers[2]}, {numbers[3], numbers[4], numbers[5]}}};
}

std::vector<int> parse_index_list(const std::string& text) {
  std::vector<int> indices;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    int value = -1;
    const char* first = text.data() + start;
    const char* last = text.data() + end;
    while (first < last && *first == ' ') ++first;  // "0, 3" as written in prose
    while (last > first && last[-1] == ' ') --last;
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
  std::vector<FilePlacement> placements;
  std::string world_file = request.world_file, color_file;
  if (!request.launch_file.empty()) {
    const YAML::Node root =
        yaml::load_map(request.launch_file, "a launch file ('world config', 'multibody configs')");
    FileReader file(request.launch_file, model);
    model.other_files.push_back(request.launch_file);
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
    if (YAML::Node at = root["at"]) {
      std::vector<std::string> listed;
      for (int index = 0; index < count; ++index)
        listed.push_back(
            resolved_path(file, configs[index], "multibody config #" + std::to_string(index))
                .lexically_normal());
      for (FilePlacement& placement : read_launch_placements(file, at, listed))
        if (std::find(adf_files.begin(), adf_files.end(), placement.file) != adf_files.end())
          placements.push_back(std::move(placement));  // the models picked with -l
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
  warn_parents_not_loaded(model);
  placements.insert(placements.end(), request.placements.begin(), request.placements.end());
  std::vector<bool> placed(adf_files.size(), false);
  for (const FilePlacement& placement : placements)
    place_file(model, adf_files, placed_file(adf_files, placement, placed), placement.placement);
  if (!color_file.empty()) {
    apply_colors(color_file, model);
    model.other_files.push_back(color_file);
  }
  return model;
}

}  // namespace afhub::physics
