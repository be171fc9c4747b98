// ADF 1.0 loader (see adf_loader.hpp). Reads each file's header lists, loads only
// the listed blocks, resolves meshes, then joints against the bodies of all files.
#include "afhub/physics/adf_loader.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "afhub/hub/channel_names.hpp"
#include "afhub/hub/error.hpp"
#include "afhub/physics/lineage.hpp"

namespace afhub::physics {
namespace {

namespace fs = std::filesystem;

constexpr const char* kDefaultNamespace = "/ambf/env/";

[[noreturn]] void fail(const SourceLocation& where, const std::string& what) {
  throw Error(where.str() + ": error: " + what);
}

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return text;
}

const char* kind_of(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Scalar:
      return "a value";
    default:
      return "nothing";
  }
}

// Reads one file's nodes with their locations.
class FileReader {
 public:
  FileReader(std::string path, Model& model) : path_(std::move(path)), model_(model) {}

  SourceLocation at(const YAML::Node& node) const {
    const YAML::Mark mark = node.Mark();
    return {path_, mark.line + 1, mark.column + 1};
  }

  double number(const YAML::Node& node, const std::string& what) const {
    if (!node.IsScalar()) fail(at(node), "'" + what + "' must be a number, not " + kind_of(node));
    double value = 0.0;
    if (!YAML::convert<double>::decode(node, value))
      fail(at(node), "'" + what + "' must be a number, got '" + node.Scalar() + "'");
    if (!std::isfinite(value))
      fail(at(node), "'" + what + "' must be finite, got '" + node.Scalar() + "'");
    return value;
  }

  double non_negative(const YAML::Node& node, const std::string& what) const {
    double value = number(node, what);
    if (value < 0.0) fail(at(node), "'" + what + "' must not be negative, got " + node.Scalar());
    return value;
  }

  bool flag(const YAML::Node& node, const std::string& what) const {
    bool value = false;
    if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value))
      fail(at(node), "'" + what + "' must be true or false");
    return value;
  }

  std::string text(const YAML::Node& node, const std::string& what) const {
    if (!node.IsScalar()) fail(at(node), "'" + what + "' must be text, not " + kind_of(node));
    return node.Scalar();
  }

  void require_map(const YAML::Node& node, const std::string& what,
                   const std::string& example) const {
    if (!node.IsMap())
      fail(at(node), "'" + what + "' must be a map such as " + example + ", not " + kind_of(node));
  }

  // Sets `out` from block[key] when the key is given; `what` names it in messages.
  void optional_non_negative(const YAML::Node& block, const char* key, double& out,
                             const std::string& what) const {
    if (YAML::Node value = block[key]) out = non_negative(value, what);
  }
  void optional_flag(const YAML::Node& block, const char* key, bool& out) const {
    if (YAML::Node value = block[key]) out = flag(value, key);
  }

  const YAML::Node require(const YAML::Node& block, const char* key,
                           const SourceLocation& where) const {
    YAML::Node value = block[key];
    if (!value) fail(where, "missing '" + std::string(key) + "'");
    return value;
  }

  Vec3 vec3(const YAML::Node& node, const std::string& what, const char* a = "x",
            const char* b = "y", const char* c = "z") const {
    if (!node.IsMap())
      fail(at(node),
           "'" + what + "' must be a map {" + a + ", " + b + ", " + c + "}, not " + kind_of(node));
    Vec3 out;
    double* slots[3] = {&out.x, &out.y, &out.z};
    const char* keys[3] = {a, b, c};
    for (int i = 0; i < 3; ++i) {
      YAML::Node component = node[keys[i]];
      if (!component) fail(at(node), "'" + what + "' is missing '" + keys[i] + "'");
      *slots[i] = number(component, what + "." + keys[i]);
    }
    return out;
  }

  Vec3 axis(const YAML::Node& node, const std::string& what) const {
    Vec3 v = vec3(node, what);
    if (std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z) < 1e-9)
      fail(at(node), "'" + what + "' has zero length; give a direction such as {x: 0, y: 0, z: 1}");
    return v;
  }

  Placement placement(const YAML::Node& node, const std::string& what) const {
    if (!node.IsMap())
      fail(at(node), "'" + what + "' must be a map with 'position' and 'orientation'");
    Placement out;
    if (YAML::Node position = node["position"]) out.position_m = vec3(position, what + ".position");
    if (YAML::Node orientation = node["orientation"])
      out.rpy_rad = vec3(orientation, what + ".orientation", "r", "p", "y");
    return out;
  }

  void warn(const YAML::Node& node, const std::string& what) const {
    model_.warnings.push_back(at(node).str() + ": warning: " + what);
  }

  void warn_unknown_keys(const YAML::Node& block, const std::set<std::string>& known,
                         const std::string& owner) const {
    for (const auto& entry : block) {
      const std::string key = entry.first.Scalar();
      if (!known.count(key))
        warn(entry.first, "unknown key '" + key + "' in " + owner + " is ignored");
    }
  }

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  Model& model_;
};

// A namespace key: absolute when it starts with '/', else inside `enclosing`.
std::string resolve_namespace(const std::string& enclosing, const std::string& given) {
  if (given.empty()) return enclosing;
  if (given.front() == '/') return given;
  return enclosing + (enclosing.ends_with('/') ? "" : "/") + given;
}

// The identifiers a header list names, with where each one is written.
std::vector<std::pair<std::string, YAML::Node>> header_list(const FileReader& file,
                                                            const YAML::Node& root,
                                                            const char* key) {
  std::vector<std::pair<std::string, YAML::Node>> out;
  YAML::Node list = root[key];
  if (!list) return out;
  if (!list.IsSequence())
    fail(file.at(list),
         std::string("'") + key + "' must be a list of identifiers, e.g. [BODY base]");
  for (const auto& item : list) {
    std::string identifier = file.text(item, std::string(key) + " entry");
    if (!root[identifier])
      fail(file.at(item), "'" + identifier + "' is listed in '" + key +
                              "' but the file has no top-level '" + identifier +
                              "' block; add the block or remove it from the list");
    out.emplace_back(identifier, item);
  }
  return out;
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
  for (const auto& candidate : tried)
    if (fs::is_regular_file(candidate)) return fs::weakly_canonical(candidate).string();
  std::string searched;
  for (const auto& candidate : tried) searched += " " + candidate.lexically_normal().string();
  fail(file.at(node), "mesh '" + name + "' not found; searched:" + searched +
                          ". Fix the name or the 'high resolution path' / 'low resolution path'");
}

// A resolution path key (file or body level), relative to the file's folder.
std::string mesh_folder(const FileReader& file, const YAML::Node& value, const fs::path& file_dir) {
  fs::path folder(file.text(value, "resolution path"));
  return (folder.is_absolute() ? folder : file_dir / folder).string();
}

const std::set<std::string> kBodyKeys = {"name",
                                         "namespace",
                                         "mesh",
                                         "shape",
                                         "geometry",
                                         "compound shape",
                                         "collision mesh",
                                         "collision mesh type",
                                         "collision shape",
                                         "collision geometry",
                                         "collision offset",
                                         "compound collision shape",
                                         "collision margin",
                                         "collision groups",
                                         "mass",
                                         "inertia",
                                         "inertial offset",
                                         "location",
                                         "scale",
                                         "friction",
                                         "damping",
                                         "restitution",
                                         "passive",
                                         "visible",
                                         "color",
                                         "color rgba",
                                         "color components",
                                         "controller",
                                         "controller output type",
                                         "publish frequency",
                                         "publish children names",
                                         "publish joint names",
                                         "publish joint positions",
                                         "high resolution path",
                                         "low resolution path",
                                         "gravity",
                                         "plugins",
                                         "shaders"};

const std::set<std::string> kJointKeys = {"name",
                                          "namespace",
                                          "parent",
                                          "child",
                                          "parent pivot",
                                          "parent axis",
                                          "child pivot",
                                          "child axis",
                                          "type",
                                          "joint limits",
                                          "offset",
                                          "joint offset",
                                          "damping",
                                          "stiffness",
                                          "equilibrium point",
                                          "enable motor",
                                          "max motor impulse",
                                          "joint erp",
                                          "joint cfm",
                                          "ignore inter-collision",
                                          "enable feedback",
                                          "controller",
                                          "controller output type",
                                          "passive",
                                          "plugins"};

struct FileContext {
  std::string name_space;
  std::string high_res_folder, low_res_folder;
  std::optional<Vec3> gravity;
  fs::path dir;
};

BodySpec read_body(const FileReader& file, const YAML::Node& block, const std::string& identifier,
                   const FileContext& context) {
  BodySpec body;
  body.identifier = identifier;
  body.where = file.at(block);
  if (!block.IsMap()) fail(body.where, "'" + identifier + "' must be a map of body keys");
  file.warn_unknown_keys(block, kBodyKeys, identifier);
  body.name = file.text(file.require(block, "name", body.where), "name");
  std::erase(body.name, ' ');
  std::string name_space = context.name_space;
  if (YAML::Node ns = block["namespace"])
    name_space = resolve_namespace(name_space, file.text(ns, "namespace"));
  body.channel = body_channel_name(name_space, body.name);
  if (auto problem = channel_name_problem(body.channel); !problem.empty())
    fail(body.where, problem);

  YAML::Node mass = block["mass"];
  if (!mass)
    fail(body.where, "'" + identifier +
                         "' has no 'mass' (AMBF would silently use 1 kg); give 'mass: 0' for a "
                         "static body or its mass in kg");
  body.mass_kg = file.non_negative(mass, "mass");
  if (YAML::Node inertia = block["inertia"]) {
    Vec3 value = file.vec3(inertia, "inertia", "ix", "iy", "iz");
    if (value.x < 0 || value.y < 0 || value.z < 0)
      fail(file.at(inertia), "'inertia' components must not be negative");
    body.inertia_kgm2 = value;
  }
  if (YAML::Node offset = block["inertial offset"])
    body.inertial_offset = file.placement(offset, "inertial offset");
  if (YAML::Node location = block["location"]) body.location = file.placement(location, "location");
  if (YAML::Node scale = block["scale"]) {
    body.scale = file.number(scale, "scale");
    if (body.scale <= 0) fail(file.at(scale), "'scale' must be positive, got " + scale.Scalar());
  }
  file.optional_flag(block, "passive", body.passive);
  if (YAML::Node friction = block["friction"]) {
    file.require_map(friction, "friction", "{static: 0.5, rolling: 0.01}");
    file.optional_non_negative(friction, "static", body.static_friction, "friction.static");
    file.optional_non_negative(friction, "rolling", body.rolling_friction, "friction.rolling");
  }
  if (YAML::Node damping = block["damping"]) {
    file.require_map(damping, "damping", "{linear: 0.04, angular: 0.1}");
    file.optional_non_negative(damping, "linear", body.linear_damping, "damping.linear");
    file.optional_non_negative(damping, "angular", body.angular_damping, "damping.angular");
  }
  file.optional_non_negative(block, "restitution", body.restitution, "restitution");
  file.optional_non_negative(block, "collision margin", body.collision_margin, "collision margin");
  if (YAML::Node groups = block["collision groups"]) {
    if (!groups.IsSequence())
      fail(file.at(groups), "'collision groups' must be a list of integers 0..999");
    for (const auto& group : groups) {
      double value = file.number(group, "collision groups entry");
      if (value < 0 || value > 999 || value != std::floor(value))
        fail(file.at(group), "collision groups are integers from 0 to 999, got " + group.Scalar());
      body.collision_groups.push_back(static_cast<int>(value));
    }
  }
  if (YAML::Node gravity = block["gravity"])
    body.gravity_mps2 = file.vec3(gravity, "gravity");
  else
    body.gravity_mps2 = context.gravity;

  std::string high = context.high_res_folder, low = context.low_res_folder;
  if (YAML::Node h = block["high resolution path"]) high = mesh_folder(file, h, context.dir);
  if (YAML::Node l = block["low resolution path"]) low = mesh_folder(file, l, context.dir);
  // `mesh: ''` (Blender exports it for an empty) means no geometry at all.
  const YAML::Node mesh_node = block["mesh"];
  const bool mesh = mesh_node && !(mesh_node.IsScalar() && mesh_node.Scalar().empty());
  YAML::Node shape = block["shape"];
  YAML::Node compound = block["compound shape"];
  const int visual_kinds = (mesh ? 1 : 0) + (shape ? 1 : 0) + (compound ? 1 : 0);
  if (visual_kinds > 1)
    fail(body.where, "'" + identifier +
                         "' gives more than one of 'mesh', 'shape' and 'compound shape'; keep one");
  if (mesh) body.visual_mesh = resolve_mesh(file, mesh_node, high, "mesh");
  if (shape) {
    static const std::set<std::string> kShapes = {"box",     "sphere", "cylinder",
                                                  "capsule", "cone",   "plane"};
    body.shape = lower(file.text(shape, "shape"));
    if (!kShapes.count(body.shape))
      fail(file.at(shape), "unknown shape '" + shape.Scalar() +
                               "'; use BOX, SPHERE, CYLINDER, CAPSULE, CONE or PLANE");
    if (!block["geometry"])
      fail(body.where, "'shape: " + shape.Scalar() + "' needs a 'geometry' map");
  }
  if (YAML::Node collision_mesh = block["collision mesh"]) {
    body.collision_mesh = resolve_mesh(file, collision_mesh, low, "collision mesh");
  } else if (mesh && !block["collision shape"] && !block["compound collision shape"]) {
    body.collision_mesh = resolve_mesh(file, mesh_node, low,
                                       "mesh (as collision mesh, from the low resolution path)");
  }
  return body;
}

JointType parse_joint_type(const FileReader& file, const YAML::Node& node) {
  static const std::map<std::string, JointType> kTypes = {
      {"hinge", JointType::kRevolute},
      {"revolute", JointType::kRevolute},
      {"continuous", JointType::kContinuous},
      {"slider", JointType::kPrismatic},
      {"prismatic", JointType::kPrismatic},
      {"fixed", JointType::kFixed},
      {"p2p", JointType::kP2P},
      {"spring", JointType::kLinearSpring},
      {"linear spring", JointType::kLinearSpring},
      {"torsion spring", JointType::kTorsionSpring},
      {"torsional spring", JointType::kTorsionSpring},
      {"angular spring", JointType::kTorsionSpring},
      {"cone twist", JointType::kConeTwist},
      {"six dof", JointType::kSixDof},
      {"six dof spring", JointType::kSixDofSpring}};
  auto found = kTypes.find(lower(file.text(node, "type")));
  if (found == kTypes.end())
    fail(file.at(node),
         "unknown joint type '" + node.Scalar() +
             "'; use revolute, continuous, prismatic, fixed, p2p, linear spring, torsion "
             "spring, cone twist, six dof or six dof spring");
  return found->second;
}

// A joint whose parent and child are still identifiers (resolved across files later).
struct PendingJoint {
  JointSpec spec;
  std::string parent, child;
  SourceLocation parent_at, child_at;
};

PendingJoint read_joint(const FileReader& file, const YAML::Node& block,
                        const std::string& identifier, const FileContext& context) {
  PendingJoint pending;
  JointSpec& joint = pending.spec;
  joint.identifier = identifier;
  joint.where = file.at(block);
  if (!block.IsMap()) fail(joint.where, "'" + identifier + "' must be a map of joint keys");
  file.warn_unknown_keys(block, kJointKeys, identifier);
  joint.name = file.text(file.require(block, "name", joint.where), "name");
  std::string name_space = context.name_space;
  if (YAML::Node ns = block["namespace"])
    name_space = resolve_namespace(name_space, file.text(ns, "namespace"));
  joint.channel = body_channel_name(name_space, joint.name);
  YAML::Node parent = file.require(block, "parent", joint.where);
  YAML::Node child = file.require(block, "child", joint.where);
  pending.parent = file.text(parent, "parent");
  pending.child = file.text(child, "child");
  pending.parent_at = file.at(parent);
  pending.child_at = file.at(child);
  joint.parent_pivot_m =
      file.vec3(file.require(block, "parent pivot", joint.where), "parent pivot");
  joint.child_pivot_m = file.vec3(file.require(block, "child pivot", joint.where), "child pivot");
  joint.parent_axis = file.axis(file.require(block, "parent axis", joint.where), "parent axis");
  joint.child_axis = file.axis(file.require(block, "child axis", joint.where), "child axis");
  joint.type = parse_joint_type(file, file.require(block, "type", joint.where));
  if (YAML::Node limits = block["joint limits"]) {
    if (!limits.IsMap())
      fail(file.at(limits), "'joint limits' must be a map such as {low: -1.57, high: 1.57}");
    if (limits["low"] && limits["high"]) {
      joint.limit_low = file.number(limits["low"], "joint limits.low");
      joint.limit_high = file.number(limits["high"], "joint limits.high");
      if (*joint.limit_low > *joint.limit_high)
        fail(file.at(limits), "'joint limits' has low " + limits["low"].Scalar() + " above high " +
                                  limits["high"].Scalar() + "; swap them");
    }
  }
  if (YAML::Node offset = block["offset"]) joint.offset_rad = file.number(offset, "offset");
  file.optional_non_negative(block, "damping", joint.damping, "damping");
  file.optional_non_negative(block, "stiffness", joint.stiffness, "stiffness");
  file.optional_non_negative(block, "max motor impulse", joint.max_motor_impulse,
                             "max motor impulse");
  file.optional_flag(block, "enable feedback", joint.enable_feedback);
  file.optional_flag(block, "passive", joint.passive);
  if (YAML::Node controller = block["controller"]) {
    if (!controller.IsMap()) fail(file.at(controller), "'controller' must be a map {P, I, D}");
    Pid pid;
    if (controller["P"]) pid.p = file.non_negative(controller["P"], "controller.P");
    if (controller["I"]) pid.i = file.non_negative(controller["I"], "controller.I");
    if (controller["D"]) pid.d = file.non_negative(controller["D"], "controller.D");
    joint.controller = pid;
  }
  return pending;
}

YAML::Node parse_file(const std::string& path) {
  if (!fs::is_regular_file(path)) throw Error(path + ": error: no such file");
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::ParserException& error) {
    throw Error(path + ":" + std::to_string(error.mark.line + 1) + ":" +
                std::to_string(error.mark.column + 1) + ": error: YAML syntax: " + error.msg);
  }
  if (root.IsNull())
    throw Error(path + ":1:1: error: the file is empty; an ADF file lists 'bodies' and 'joints'");
  if (!root.IsMap())
    throw Error(path + ":1:1: error: an ADF file is a map of keys, not " + kind_of(root));
  return root;
}

// Reads one file's header, bodies and (still unresolved) joints.
void load_file(const std::string& path, const YAML::Node& root, Model& model,
               std::vector<PendingJoint>& pending, std::map<std::string, int>& body_by_identifier) {
  FileReader file(path, model);

  FileContext context;
  context.dir = fs::path(path).parent_path();
  context.name_space = kDefaultNamespace;
  if (YAML::Node ns = root["namespace"])
    context.name_space = resolve_namespace(kDefaultNamespace, file.text(ns, "namespace"));
  context.high_res_folder = context.low_res_folder = context.dir.string();
  if (YAML::Node h = root["high resolution path"])
    context.high_res_folder = mesh_folder(file, h, context.dir);
  if (YAML::Node l = root["low resolution path"])
    context.low_res_folder = mesh_folder(file, l, context.dir);
  if (YAML::Node gravity = root["gravity"]) context.gravity = file.vec3(gravity, "gravity");
  if (!root["bodies"] && !root["joints"])
    model.warnings.push_back(
        path + ":1:1: warning: no 'bodies' or 'joints' list: nothing is loaded from this file");

  for (const auto& [identifier, listed] : header_list(file, root, "bodies")) {
    if (body_by_identifier.count(identifier))
      fail(file.at(listed), "'" + identifier + "' is defined twice (first at " +
                                model.bodies[body_by_identifier[identifier]].where.str() + ")");
    body_by_identifier[identifier] = static_cast<int>(model.bodies.size());
    model.bodies.push_back(read_body(file, root[identifier], identifier, context));
  }
  for (const auto& [identifier, listed] : header_list(file, root, "joints"))
    pending.push_back(read_joint(file, root[identifier], identifier, context));
}

}  // namespace

Model load_adf_files(const std::vector<std::string>& paths) {
  Model model;
  std::vector<PendingJoint> pending;
  std::map<std::string, int> body_by_identifier;
  for (const std::string& path : paths) {
    YAML::Node root = parse_file(path);
    try {
      load_file(path, root, model, pending, body_by_identifier);
    } catch (const YAML::Exception& error) {
      // A key looked up inside a scalar or a list, for instance.
      throw Error(path + ":" + std::to_string(error.mark.line + 1) + ":" +
                  std::to_string(error.mark.column + 1) + ": error: " + error.msg);
    }
  }

  for (PendingJoint& joint : pending) {
    auto parent = body_by_identifier.find(joint.parent);
    if (parent == body_by_identifier.end())
      fail(joint.parent_at,
           "parent '" + joint.parent + "' of " + joint.spec.identifier +
               " is not a loaded body; list it in a 'bodies' header of a loaded file");
    auto child = body_by_identifier.find(joint.child);
    if (child == body_by_identifier.end())
      fail(joint.child_at,
           "child '" + joint.child + "' of " + joint.spec.identifier +
               " is not a loaded body; list it in a 'bodies' header of a loaded file");
    if (parent->second == child->second)
      fail(joint.child_at, joint.spec.identifier + " joins '" + joint.child +
                               "' to itself; parent and child must differ");
    joint.spec.parent = parent->second;
    joint.spec.child = child->second;
    model.joints.push_back(joint.spec);
  }
  compute_lineage(model);
  return model;
}

}  // namespace afhub::physics
