// ADF 1.0 loader (see adf_loader.hpp). Reads each file's header lists and loads
// only the listed blocks, each with its reader (body_reader.cpp, joint_reader.cpp,
// soft_body_reader.cpp, sensor_reader.cpp, actuator_reader.cpp); then resolves
// joints, sensors and actuators against the bodies of all files, and computes the
// lineage. Block names are scoped per file and references resolve by AMBF's rule
// (body_scope.cpp); a model loaded twice gets distinct channels (loaded_copies.cpp).
// The helpers the readers share are here too.
#include "afhub/physics/adf_loader.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <map>
#include <unordered_set>

#include "adf_blocks.hpp"
#include "afhub/physics/lineage.hpp"
#include "afhub/shm_layout/error.hpp"
#include "body_scope.hpp"
#include "loaded_copies.hpp"
#include "path_kind.hpp"

namespace afhub::physics {
namespace adf {

namespace fs = std::filesystem;

std::string block_namespace(const FileReader& file, const YAML::Node& block,
                            const FileContext& context) {
  if (YAML::Node ns = block["namespace"])
    return resolve_namespace(context.name_space, file.text(ns, "namespace"));
  return context.name_space;
}

std::string resolve_mesh(const FileReader& file, const YAML::Node& node, const std::string& folder,
                         const std::string& what) {
  const std::string name = file.text(node, what);
  std::vector<fs::path> tried;
  fs::path direct(name);
  if (direct.is_absolute()) {
    tried.push_back(direct);
  } else {
    tried.push_back(fs::path(folder) / name);
  }
  std::string searched;
  for (const auto& candidate : tried) {
    const std::string why = not_a_regular_file(candidate);
    if (why.empty()) {
      std::error_code error;
      const fs::path canonical = fs::weakly_canonical(candidate, error);
      return (error ? candidate : canonical).string();
    }
    searched += " " + candidate.lexically_normal().string() + " (" + why + ")";
  }
  fail(file.at(node), "mesh '" + name + "' is not a readable file:" + searched +
                          ". Fix the name or the 'high resolution path' / 'low resolution path'");
}

// A resolution path key (file or body level), relative to the file's folder.
std::string mesh_folder(const FileReader& file, const YAML::Node& value, const fs::path& file_dir) {
  fs::path folder(file.text(value, "resolution path"));
  return (folder.is_absolute() ? folder : file_dir / folder).string();
}

double positive(const FileReader& file, const YAML::Node& node, const std::string& what) {
  if (!node) fail(file.at(node), "missing '" + what + "'");
  return file.positive(node, what);
}

Pid read_pid(const FileReader& file, const YAML::Node& node, const std::string& what) {
  file.require_map(node, what, "{P: 10, I: 0, D: 1}");
  Pid pid;
  file.optional_non_negative(node, "P", pid.p, what + ".P");
  file.optional_non_negative(node, "I", pid.i, what + ".I");
  file.optional_non_negative(node, "D", pid.d, what + ".D");
  return pid;
}

ControllerOutput read_output_type(const FileReader& file, const YAML::Node& node) {
  const std::string type = lower(file.text(node, "controller output type"));
  if (type == "force") return ControllerOutput::kForce;
  if (type == "velocity") return ControllerOutput::kVelocity;
  fail(file.at(node), "'controller output type' must be FORCE or VELOCITY, got " + node.Scalar());
}

void read_parent(const FileReader& file, const YAML::Node& block, const SourceLocation& where,
                 PendingParent& pending) {
  const YAML::Node parent = file.require(block, "parent", where);
  pending.parent = file.text(parent, "parent");
  pending.parent_at = file.at(parent);
}

}  // namespace adf

namespace {

using namespace adf;

constexpr const char* kDefaultNamespace = "/ambf/env/";

// Reads one file's header, bodies and (still unresolved) joints.
struct Unresolved {
  std::vector<PendingJoint> joints;
  std::vector<PendingParent> parents;
  std::size_t published_bodies = 0;  // refused at once past the hub's limit
};

void load_file(const std::string& path, const YAML::Node& root, Model& model, Unresolved& pending) {
  FileReader file(path, model);
  const yaml::MapIndex index(file, root);
  auto key = [&](const char* name) { return index.find(name); };

  // Not otherwise read (every AMBF file says 1.0), but a list or a map there is a slip.
  if (const YAML::Node* version = key("adf version")) file.text(*version, "adf version");
  FileContext context;
  context.dir = fs::path(path).parent_path();
  context.name_space = kDefaultNamespace;
  if (const YAML::Node* ns = key("namespace"))
    context.name_space = resolve_namespace(kDefaultNamespace, file.text(*ns, "namespace"));
  context.high_res_folder = context.low_res_folder = context.dir.string();
  if (const YAML::Node* h = key("high resolution path"))
    context.high_res_folder = mesh_folder(file, *h, context.dir);
  if (const YAML::Node* l = key("low resolution path"))
    context.low_res_folder = mesh_folder(file, *l, context.dir);
  if (const YAML::Node* gravity = key("gravity")) context.gravity = file.gravity(*gravity);
  context.file_index = static_cast<int>(model.file_ignores_inter_collision.size());
  bool ignore_inter_collision = false;
  if (const YAML::Node* ignore = key("ignore inter-collision"))
    ignore_inter_collision = file.flag(*ignore, "ignore inter-collision");
  model.file_ignores_inter_collision.push_back(ignore_inter_collision);
  model.file_parts_overlaps.push_back(false);
  // A launch or world file given as a model loaded nothing and ran an empty world.
  if (!key("bodies") && !key("joints") && !key("soft bodies")) {
    if (key("multibody configs"))
      throw Error(path +
                  ":1:1: error: this is a launch file ('multibody configs'), not a model: "
                  "give it with --launch " +
                  path + " -l 0,1 (the indices of the models to load)");
    if (key("lights") || key("cameras") || key("environment") || key("enclosure"))
      throw Error(path +
                  ":1:1: error: this is a world file (lights, cameras, environment), "
                  "not a model: give it with --world " +
                  path + " beside the model files");
    model.warnings.push_back(
        path + ":1:1: warning: no 'bodies' or 'joints' list: nothing is loaded from this file");
  }

  // Block names are scoped per file (as in AMBF): another file may use the same ones.
  std::map<std::string, std::size_t> body_in_file;
  const std::vector<ListedBlock> bodies = header_list(file, index, "bodies");
  if (!bodies.empty())
    count_model_bodies(model.bodies.size() + bodies.size(), file.at(bodies.front().listed));
  for (const auto& [identifier, listed, block] : bodies) {
    if (auto [first, added] = body_in_file.try_emplace(identifier, model.bodies.size()); !added)
      fail(file.at(listed), "'" + identifier + "' is listed twice (first defined at " +
                                model.bodies[first->second].where.str() + ")");
    model.bodies.push_back(read_body(file, block, identifier, context));
    if (!model.bodies.back().passive)
      count_published_body(identifier, model.bodies.back().where, pending.published_bodies);
  }
  const std::vector<ListedBlock> soft_bodies = header_list(file, index, "soft bodies");
  if (!soft_bodies.empty())
    count_model_bodies(model.bodies.size() + model.soft_bodies.size() + soft_bodies.size(),
                       file.at(soft_bodies.front().listed));
  for (const auto& [identifier, listed, block] : soft_bodies) {
    model.soft_bodies.push_back(read_soft_body(file, block, identifier, context));
    count_published_body(identifier, model.soft_bodies.back().where, pending.published_bodies);
  }
  for (const auto& [identifier, listed, block] : header_list(file, index, "sensors")) {
    PendingParent parent{true, model.sensors.size(), {}, {}, {}};
    parent.from = {context.file_index, block_namespace(file, block, context)};
    model.sensors.push_back(read_sensor(file, block, identifier, parent));
    pending.parents.push_back(parent);
  }
  for (const auto& [identifier, listed, block] : header_list(file, index, "actuators")) {
    PendingParent parent{false, model.actuators.size(), {}, {}, {}};
    parent.from = {context.file_index, block_namespace(file, block, context)};
    model.actuators.push_back(read_actuator(file, block, identifier, parent));
    pending.parents.push_back(parent);
  }
  for (const auto& [identifier, listed, block] : header_list(file, index, "joints"))
    pending.joints.push_back(read_joint(file, block, identifier, context));
}

}  // namespace

void load_adf_files_into(const std::vector<std::string>& paths, Model& model,
                         const UrdfOptions& urdf) {
  Unresolved pending;
  LoadedChannels channels;
  std::vector<std::string> copy_suffix;  // per body: the index a copy's name got
  for (const std::string& path : paths) {
    if (is_urdf_path(path)) {
      const FileSpan span{path, model.bodies.size(), model.soft_bodies.size(),
                          pending.joints.size(), model.joints.size()};
      load_urdf_into(path, urdf, model);
      channels.load_as_copies(span, model, pending.joints, copy_suffix);
      continue;
    }
    YAML::Node root = yaml::load_map(path, "an ADF file (a map with 'bodies' and 'joints' lists)");
    const FileSpan span{path, model.bodies.size(), model.soft_bodies.size(), pending.joints.size(),
                        model.joints.size()};
    try {
      load_file(path, root, model, pending);
    } catch (const YAML::Exception& error) {
      // A key looked up inside a scalar or a list, for instance.
      throw Error(path + ":" + std::to_string(error.mark.line + 1) + ":" +
                  std::to_string(error.mark.column + 1) + ": error: " + error.msg);
    }
    channels.load_as_copies(span, model, pending.joints, copy_suffix);
  }

  // Joints resolve once every body exists, as in AMBF: a joint may join bodies of
  // other files (the distributed definition).
  const BodyScope scope(model, copy_suffix);
  for (PendingJoint& joint : pending.joints) {
    const std::string& owner = joint.spec.identifier;
    joint.spec.parent = scope.find(joint.parent, joint.from, joint.parent_at, "parent", owner);
    joint.spec.child = scope.find(joint.child, joint.from, joint.child_at, "child", owner);
    if (joint.spec.parent == joint.spec.child)
      fail(joint.child_at, joint.spec.identifier + " joins '" + joint.child +
                               "' to itself; parent and child must differ");
    model.joints.push_back(joint.spec);
  }
  for (const PendingParent& item : pending.parents) {
    const std::string& owner =
        item.sensor ? model.sensors[item.index].identifier : model.actuators[item.index].identifier;
    const int body = scope.find(item.parent, item.from, item.parent_at, "parent", owner);
    (item.sensor ? model.sensors[item.index].parent : model.actuators[item.index].parent) = body;
  }
  // Sensors and actuators are found by name in their body's namespace: a name met there
  // before gets the smallest index that frees it, as AMBF names copies (the two grippers
  // of AMBF's input devices file had one "Proximity0", the first's, and one
  // "Constraint0", the second's; now the second's are "Proximity01" and "Constraint01").
  std::unordered_set<std::string> taken;
  const auto name_freely = [&](std::string& name, int parent) {
    const std::string& channel = parent >= 0 ? model.bodies[parent].channel : std::string();
    const std::string space = channel.substr(0, channel.rfind('/') + 1);
    std::string free = name;
    for (int index = 1; !taken.insert(space + free).second; ++index)
      free = name + std::to_string(index);
    name = free;
  };
  for (SensorSpec& sensor : model.sensors) name_freely(sensor.name, sensor.parent);
  for (ActuatorSpec& actuator : model.actuators) name_freely(actuator.name, actuator.parent);
  compute_lineage(model);
  check_model(model);
}

Model load_adf_files(const std::vector<std::string>& paths) {
  Model model;
  load_adf_files_into(paths, model);
  return model;
}

}  // namespace afhub::physics
