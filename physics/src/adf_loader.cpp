// ADF 1.0 loader (see adf_loader.hpp). Reads each file's header lists, loads only
// the listed blocks, resolves meshes, then joints against the bodies of all files.
#include "afhub/physics/adf_loader.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "afhub/physics/lineage.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "yaml_reader.hpp"

namespace afhub::physics {
namespace {

namespace fs = std::filesystem;

constexpr const char* kDefaultNamespace = "/ambf/env/";

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
  int file_index = 0;
};

// What every block starts with: where it is, that it is a map, its keys, its name.
template <class Spec>
void read_block_head(const FileReader& file, const YAML::Node& block, const std::string& identifier,
                     const std::set<std::string>& keys, const char* kind, Spec& spec) {
  spec.identifier = identifier;
  spec.where = file.at(block);
  if (!block.IsMap()) fail(spec.where, "'" + identifier + "' must be a map of " + kind + " keys");
  file.warn_unknown_keys(block, keys, identifier);
  spec.name = file.text(file.require(block, "name", spec.where), "name");
}

ShapeKind read_shape_kind(const FileReader& file, const YAML::Node& node) {
  static const std::map<std::string, ShapeKind> kShapes = {
      {"box", ShapeKind::kBox},           {"sphere", ShapeKind::kSphere},
      {"cylinder", ShapeKind::kCylinder}, {"capsule", ShapeKind::kCapsule},
      {"cone", ShapeKind::kCone},         {"plane", ShapeKind::kPlane}};
  auto found = kShapes.find(lower(file.text(node, "shape")));
  if (found == kShapes.end())
    fail(file.at(node), "unknown shape '" + node.Scalar() +
                            "'; use BOX, SPHERE, CYLINDER, CAPSULE, CONE or PLANE");
  return found->second;
}

double positive(const FileReader& file, const YAML::Node& node, const std::string& what) {
  if (!node) fail(file.at(node), "missing '" + what + "'");
  const double value = file.number(node, what);
  if (value <= 0.0) fail(file.at(node), "'" + what + "' must be positive, got " + node.Scalar());
  return value;
}

// A primitive: `kind_node` is the shape's name, `geometry` its sizes; `owner` is
// the block, for the location of a missing geometry.
ShapeSpec read_shape(const FileReader& file, const YAML::Node& kind_node,
                     const YAML::Node& geometry, const std::string& what, const YAML::Node& owner) {
  ShapeSpec shape;
  shape.kind = read_shape_kind(file, kind_node);
  if (!geometry)
    fail(file.at(owner), "'shape: " + kind_node.Scalar() + "' needs a '" + what + "' map");
  file.require_map(geometry, what, "{radius: 0.1}");
  auto size = [&](const char* key) {
    YAML::Node value = geometry[key];
    if (!value)
      fail(file.at(geometry), "'" + what + "' of a " + kind_node.Scalar() + " needs '" + key + "'");
    return positive(file, value, what + "." + key);
  };
  switch (shape.kind) {
    case ShapeKind::kBox:
      shape.box_size_m = {size("x"), size("y"), size("z")};
      break;
    case ShapeKind::kSphere:
      shape.radius_m = size("radius");
      break;
    case ShapeKind::kCylinder:
    case ShapeKind::kCapsule:
    case ShapeKind::kCone:
      shape.radius_m = size("radius");
      shape.height_m = size("height");
      if (YAML::Node axis = geometry["axis"]) {
        const std::string name = lower(file.text(axis, what + ".axis"));
        if (name != "x" && name != "y" && name != "z")
          fail(file.at(axis), "'" + what + ".axis' must be X, Y or Z, got " + axis.Scalar());
        shape.axis = name[0] - 'x';
      }
      break;
    case ShapeKind::kPlane:
      if (!geometry["normal"]) fail(file.at(geometry), "'" + what + "' of a PLANE needs 'normal'");
      shape.plane_normal = file.axis(geometry["normal"], what + ".normal");
      shape.plane_offset_m =
          geometry["offset"] ? file.number(geometry["offset"], what + ".offset") : 0.0;
      break;
  }
  return shape;
}

std::vector<ShapeSpec> read_compound(const FileReader& file, const YAML::Node& list,
                                     const std::string& what) {
  if (!list.IsSequence() || list.size() == 0)
    fail(file.at(list), "'" + what + "' must be a non-empty list of {shape, geometry, offset}");
  std::vector<ShapeSpec> shapes;
  for (const auto& entry : list) {
    file.require_map(entry, what + " entry", "{shape: BOX, geometry: {x: 1, y: 1, z: 1}}");
    YAML::Node kind = entry["shape"];
    if (!kind) fail(file.at(entry), "'" + what + "' entry needs 'shape'");
    ShapeSpec shape = read_shape(file, kind, entry["geometry"], "geometry", entry);
    if (YAML::Node offset = entry["offset"]) shape.offset = file.placement(offset, "offset");
    shapes.push_back(shape);
  }
  return shapes;
}

// `scale` applies to primitives as it does to meshes: sizes and offsets.
void scale_shapes(std::vector<ShapeSpec>& shapes, double scale) {
  for (ShapeSpec& shape : shapes) {
    shape.box_size_m = {shape.box_size_m.x * scale, shape.box_size_m.y * scale,
                        shape.box_size_m.z * scale};
    shape.radius_m *= scale;
    shape.height_m *= scale;
    shape.plane_offset_m *= scale;
    Vec3& p = shape.offset.position_m;
    p = {p.x * scale, p.y * scale, p.z * scale};
  }
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

// Colors are kept for a future viewer: `color rgba`, `color components` or a named `color`.
void read_color(const FileReader& file, const YAML::Node& block, BodySpec& body) {
  if (YAML::Node rgba = block["color rgba"]) {
    file.require_map(rgba, "color rgba", "{r: 1, g: 0, b: 0, a: 1}");
    std::array<double, 4> color{0.0, 0.0, 0.0, 1.0};
    const char* keys[4] = {"r", "g", "b", "a"};
    for (int i = 0; i < 4; ++i)
      file.optional_non_negative(rgba, keys[i], color[i], std::string("color rgba.") + keys[i]);
    body.color_rgba = color;
  } else if (YAML::Node components = block["color components"]) {
    file.require_map(components, "color components", "{diffuse: {r, g, b}, transparency: 1}");
    std::array<double, 4> color{0.5, 0.5, 0.5, 1.0};
    if (YAML::Node diffuse = components["diffuse"]) {
      file.require_map(diffuse, "color components.diffuse", "{r: 1, g: 0, b: 0}");
      const char* keys[3] = {"r", "g", "b"};
      for (int i = 0; i < 3; ++i)
        file.optional_non_negative(diffuse, keys[i], color[i],
                                   std::string("color components.diffuse.") + keys[i]);
    }
    file.optional_non_negative(components, "transparency", color[3],
                               "color components.transparency");
    body.color_rgba = color;
  }
  if (YAML::Node name = block["color"]) body.color_name = file.text(name, "color");
}

BodySpec read_body(const FileReader& file, const YAML::Node& block, const std::string& identifier,
                   const FileContext& context) {
  BodySpec body;
  read_block_head(file, block, identifier, kBodyKeys, "body", body);
  body.file_index = context.file_index;
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
  if (shape)
    body.visual_shapes.push_back(read_shape(file, shape, block["geometry"], "geometry", block));
  if (compound) body.visual_shapes = read_compound(file, compound, "compound shape");

  if (YAML::Node type = block["collision mesh type"]) {
    static const std::map<std::string, CollisionMeshType> kTypes = {
        {"convex_hull", CollisionMeshType::kConvexHull},
        {"convex_mesh", CollisionMeshType::kConvexMesh},
        {"trimesh", CollisionMeshType::kTrimesh},
        {"point_cloud", CollisionMeshType::kPointCloud}};
    auto found = kTypes.find(lower(file.text(type, "collision mesh type")));
    if (found == kTypes.end())
      fail(file.at(type), "unknown collision mesh type '" + type.Scalar() +
                              "'; use CONVEX_HULL, CONVEX_MESH, TRIMESH or POINT_CLOUD");
    body.collision_mesh_type = found->second;
  }
  if (YAML::Node offset = block["collision offset"])
    body.collision_offset = file.placement(offset, "collision offset");
  YAML::Node collision_shape = block["collision shape"];
  YAML::Node collision_compound = block["compound collision shape"];
  YAML::Node collision_mesh = block["collision mesh"];
  if ((collision_shape ? 1 : 0) + (collision_compound ? 1 : 0) + (collision_mesh ? 1 : 0) > 1)
    fail(body.where, "'" + identifier +
                         "' gives more than one of 'collision mesh', 'collision shape' and "
                         "'compound collision shape'; keep one");
  if (collision_shape) {
    ShapeSpec spec =
        read_shape(file, collision_shape, block["collision geometry"], "collision geometry", block);
    // Upstream: a primitive collision shape without its own offset sits at the inertial offset.
    if (body.collision_offset)
      spec.offset = *body.collision_offset;
    else if (body.inertial_offset)
      spec.offset = *body.inertial_offset;
    body.collision_shapes.push_back(spec);
  } else if (collision_compound) {
    body.collision_shapes = read_compound(file, collision_compound, "compound collision shape");
  } else if (collision_mesh) {
    body.collision_mesh = resolve_mesh(file, collision_mesh, low, "collision mesh");
  } else if (mesh) {
    body.collision_mesh = resolve_mesh(file, mesh_node, low,
                                       "mesh (as collision mesh, from the low resolution path)");
  } else {
    body.collision_shapes = body.visual_shapes;
  }

  scale_shapes(body.visual_shapes, body.scale);
  scale_shapes(body.collision_shapes, body.scale);
  if (YAML::Node controller = block["controller"]) {
    file.require_map(controller, "controller", "{linear: {P, I, D}, angular: {P, I, D}}");
    if (YAML::Node linear = controller["linear"])
      body.linear_controller = read_pid(file, linear, "controller.linear");
    if (YAML::Node angular = controller["angular"])
      body.angular_controller = read_pid(file, angular, "controller.angular");
  }
  if (YAML::Node output = block["controller output type"])
    body.controller_output = read_output_type(file, output);
  read_color(file, block, body);
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

void read_joint_limits(const FileReader& file, const YAML::Node& limits, JointSpec& joint) {
  file.require_map(limits, "joint limits", "{low: -1.57, high: 1.57}");
  if (joint.type == JointType::kConeTwist) {
    if (limits.size() == 0) return;
    SixDofLimits cone;
    cone.angular_high = file.vec3(limits, "joint limits");
    joint.multi_limits = cone;
    return;
  }
  if (joint.type == JointType::kSixDof || joint.type == JointType::kSixDofSpring) {
    if (limits.size() == 0) return;
    SixDofLimits six;
    auto pair = [&](const char* group, Vec3& low, Vec3& high) {
      YAML::Node node = limits[group];
      if (!node) return;
      file.require_map(node, std::string("joint limits.") + group,
                       "{low: {x, y, z}, high: {x, y, z}}");
      if (node["low"]) low = file.vec3(node["low"], std::string("joint limits.") + group + ".low");
      if (node["high"])
        high = file.vec3(node["high"], std::string("joint limits.") + group + ".high");
    };
    pair("linear", six.linear_low, six.linear_high);
    pair("angular", six.angular_low, six.angular_high);
    joint.multi_limits = six;
    return;
  }
  // 1-DOF limits apply only when both ends are given, as upstream.
  if (limits["low"] && limits["high"]) {
    joint.limit_low = file.number(limits["low"], "joint limits.low");
    joint.limit_high = file.number(limits["high"], "joint limits.high");
    if (*joint.limit_low > *joint.limit_high)
      fail(file.at(limits), "'joint limits' has low " + limits["low"].Scalar() + " above high " +
                                limits["high"].Scalar() + "; swap them");
  }
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
  read_block_head(file, block, identifier, kJointKeys, "joint", joint);
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
  if (YAML::Node limits = block["joint limits"]) read_joint_limits(file, limits, joint);
  if (YAML::Node offset = block["offset"]) joint.offset_rad = file.number(offset, "offset");
  if (YAML::Node offset = block["joint offset"])
    joint.joint_offset_rad = file.number(offset, "joint offset");
  file.optional_non_negative(block, "damping", joint.damping, "damping");
  file.optional_non_negative(block, "stiffness", joint.stiffness, "stiffness");
  if (YAML::Node equilibrium = block["equilibrium point"])
    joint.equilibrium = file.number(equilibrium, "equilibrium point");
  file.optional_non_negative(block, "max motor impulse", joint.max_motor_impulse,
                             "max motor impulse");
  if (YAML::Node erp = block["joint erp"]) joint.erp = file.non_negative(erp, "joint erp");
  if (YAML::Node cfm = block["joint cfm"]) joint.cfm = file.non_negative(cfm, "joint cfm");
  file.optional_flag(block, "ignore inter-collision", joint.ignore_inter_collision);
  file.optional_flag(block, "enable feedback", joint.enable_feedback);
  file.optional_flag(block, "passive", joint.passive);
  if (YAML::Node motor = block["enable motor"]) {
    file.flag(motor, "enable motor");  // checked; motors are enabled by velocity commands
  }
  if (YAML::Node controller = block["controller"])
    joint.controller = read_pid(file, controller, "controller");
  if (YAML::Node output = block["controller output type"])
    joint.controller_output = read_output_type(file, output);
  return pending;
}

// A sensor's or actuator's parent, resolved once every file is loaded.
struct PendingParent {
  bool sensor = true;
  std::size_t index = 0;
  std::string parent;
  SourceLocation parent_at;
};

void read_parent(const FileReader& file, const YAML::Node& block, const SourceLocation& where,
                 PendingParent& pending) {
  const YAML::Node parent = file.require(block, "parent", where);
  pending.parent = file.text(parent, "parent");
  pending.parent_at = file.at(parent);
}

const std::set<std::string> kSoftBodyKeys = {"name",
                                             "namespace",
                                             "mesh",
                                             "mass",
                                             "location",
                                             "scale",
                                             "config",
                                             "high resolution path",
                                             "low resolution path",
                                             "color",
                                             "color rgba",
                                             "color components",
                                             "collision margin",
                                             "randomize constraints",
                                             "publish frequency",
                                             "plugins"};

SoftBodySpec read_soft_body(const FileReader& file, const YAML::Node& block,
                            const std::string& identifier, const FileContext& context) {
  SoftBodySpec soft;
  read_block_head(file, block, identifier, kSoftBodyKeys, "soft body", soft);
  std::erase(soft.name, ' ');
  std::string name_space = context.name_space;
  if (YAML::Node ns = block["namespace"])
    name_space = resolve_namespace(name_space, file.text(ns, "namespace"));
  soft.channel = body_channel_name(name_space, soft.name);
  soft.mass_kg = positive(file, file.require(block, "mass", soft.where), "mass");
  if (YAML::Node location = block["location"]) soft.location = file.placement(location, "location");
  if (YAML::Node scale = block["scale"]) soft.scale = positive(file, scale, "scale");
  std::string high = context.high_res_folder;
  if (YAML::Node h = block["high resolution path"]) high = mesh_folder(file, h, context.dir);
  soft.mesh = resolve_mesh(file, file.require(block, "mesh", soft.where), high, "mesh");
  if (YAML::Node config = block["config"]) {
    file.require_map(config, "config", "{kLST: 0.5, piterations: 10, fixed nodes: [0, 1]}");
    for (const auto& entry : config) {
      const std::string key = entry.first.Scalar();
      if (key == "fixed nodes") {
        if (!entry.second.IsSequence())
          fail(file.at(entry.second), "'config.fixed nodes' must be a list of node indices");
        for (const auto& node : entry.second) {
          const double index = file.non_negative(node, "config.fixed nodes entry");
          if (index != std::floor(index))
            fail(file.at(node), "'config.fixed nodes' entries are node indices (integers)");
          soft.fixed_nodes.push_back(static_cast<int>(index));
        }
      } else if (key == "bending constraint") {
        soft.bending_constraint =
            static_cast<int>(file.non_negative(entry.second, "config.bending constraint"));
      } else if (key == "clusters") {
        soft.clusters = static_cast<int>(file.non_negative(entry.second, "config.clusters"));
      } else if (entry.second.IsScalar()) {
        bool flag_value = false;
        if (YAML::convert<bool>::decode(entry.second, flag_value) &&
            !std::isdigit(static_cast<unsigned char>(entry.second.Scalar()[0])))
          soft.config.emplace_back(key, flag_value ? 1.0 : 0.0);
        else
          soft.config.emplace_back(key, file.number(entry.second, "config." + key));
      } else {
        file.warn(entry.first, "soft body config '" + key + "' is not a value and is ignored");
      }
    }
  }
  return soft;
}

const std::set<std::string> kSensorKeys = {
    "name",  "namespace",  "type",    "parent",       "location",          "range",
    "array", "parametric", "visible", "visible size", "publish frequency", "plugins"};

SensorSpec read_sensor(const FileReader& file, const YAML::Node& block,
                       const std::string& identifier, PendingParent& pending) {
  SensorSpec sensor;
  read_block_head(file, block, identifier, kSensorKeys, "sensor", sensor);
  const YAML::Node type = file.require(block, "type", sensor.where);
  const std::string kind = lower(file.text(type, "type"));
  if (kind != "proximity" && kind != "resistance")
    fail(file.at(type), "unknown sensor type '" + type.Scalar() + "'; use Proximity or Resistance");
  read_parent(file, block, sensor.where, pending);
  if (YAML::Node location = block["location"])
    sensor.location = file.placement(location, "location");
  if (YAML::Node range = block["range"]) sensor.range_m = positive(file, range, "range");
  if (YAML::Node array = block["array"]) {
    if (!array.IsSequence() || array.size() == 0)
      fail(file.at(array), "'array' must be a non-empty list of {offset, direction}");
    for (const auto& ray : array) {
      file.require_map(ray, "array entry", "{offset: {x, y, z}, direction: {x, y, z}}");
      Vec3 offset;
      if (ray["offset"]) offset = file.vec3(ray["offset"], "array.offset");
      sensor.rays.emplace_back(
          offset, file.axis(file.require(ray, "direction", file.at(ray)), "array.direction"));
    }
  } else if (YAML::Node parametric = block["parametric"]) {
    file.require_map(parametric, "parametric", "{resolution: 4, horizontal angle: 0.5, ...}");
    const int resolution =
        static_cast<int>(positive(file, file.require(parametric, "resolution", file.at(parametric)),
                                  "parametric.resolution"));
    double horizontal = 0.0, vertical = 0.0, start = 0.0;
    file.optional_non_negative(parametric, "horizontal angle", horizontal,
                               "parametric.horizontal angle");
    file.optional_non_negative(parametric, "vertical angle", vertical, "parametric.vertical angle");
    file.optional_non_negative(parametric, "start offset", start, "parametric.start offset");
    // resolution^2 rays spread over the two angles, pointing along +x of the sensor.
    for (int i = 0; i < resolution; ++i)
      for (int j = 0; j < resolution; ++j) {
        const double u = resolution > 1 ? static_cast<double>(i) / (resolution - 1) - 0.5 : 0.0;
        const double v = resolution > 1 ? static_cast<double>(j) / (resolution - 1) - 0.5 : 0.0;
        const double yaw = u * horizontal, pitch = v * vertical;
        Vec3 direction{std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw),
                       std::sin(pitch)};
        sensor.rays.emplace_back(
            Vec3{direction.x * start, direction.y * start, direction.z * start}, direction);
      }
  } else {
    fail(sensor.where, "'" + identifier + "' needs 'array' or 'parametric' to define its rays");
  }
  return sensor;
}

const std::set<std::string> kActuatorKeys = {
    "name",         "namespace",         "type",   "parent",
    "location",     "max impulse",       "tau",    "visible",
    "visible size", "publish frequency", "plugins"};

ActuatorSpec read_actuator(const FileReader& file, const YAML::Node& block,
                           const std::string& identifier, PendingParent& pending) {
  ActuatorSpec actuator;
  read_block_head(file, block, identifier, kActuatorKeys, "actuator", actuator);
  const YAML::Node type = file.require(block, "type", actuator.where);
  if (lower(file.text(type, "type")) != "constraint")
    fail(file.at(type), "unknown actuator type '" + type.Scalar() + "'; use Constraint");
  read_parent(file, block, actuator.where, pending);
  if (YAML::Node location = block["location"])
    actuator.location = file.placement(location, "location");
  if (YAML::Node impulse = block["max impulse"])
    actuator.max_impulse = positive(file, impulse, "max impulse");
  if (YAML::Node tau = block["tau"]) actuator.tau = positive(file, tau, "tau");
  return actuator;
}

// Reads one file's header, bodies and (still unresolved) joints.
struct Unresolved {
  std::vector<PendingJoint> joints;
  std::vector<PendingParent> parents;
};

void load_file(const std::string& path, const YAML::Node& root, Model& model, Unresolved& pending,
               std::map<std::string, int>& body_by_identifier) {
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
  context.file_index = static_cast<int>(model.file_ignores_inter_collision.size());
  bool ignore_inter_collision = false;
  file.optional_flag(root, "ignore inter-collision", ignore_inter_collision);
  model.file_ignores_inter_collision.push_back(ignore_inter_collision);
  if (!root["bodies"] && !root["joints"] && !root["soft bodies"])
    model.warnings.push_back(
        path + ":1:1: warning: no 'bodies' or 'joints' list: nothing is loaded from this file");

  for (const auto& [identifier, listed] : header_list(file, root, "bodies")) {
    if (body_by_identifier.count(identifier))
      fail(file.at(listed), "'" + identifier + "' is defined twice (first at " +
                                model.bodies[body_by_identifier[identifier]].where.str() + ")");
    body_by_identifier[identifier] = static_cast<int>(model.bodies.size());
    model.bodies.push_back(read_body(file, root[identifier], identifier, context));
  }
  for (const auto& [identifier, listed] : header_list(file, root, "soft bodies"))
    model.soft_bodies.push_back(read_soft_body(file, root[identifier], identifier, context));
  for (const auto& [identifier, listed] : header_list(file, root, "sensors")) {
    PendingParent parent{true, model.sensors.size(), {}, {}};
    model.sensors.push_back(read_sensor(file, root[identifier], identifier, parent));
    pending.parents.push_back(parent);
  }
  for (const auto& [identifier, listed] : header_list(file, root, "actuators")) {
    PendingParent parent{false, model.actuators.size(), {}, {}};
    model.actuators.push_back(read_actuator(file, root[identifier], identifier, parent));
    pending.parents.push_back(parent);
  }
  for (const auto& [identifier, listed] : header_list(file, root, "joints"))
    pending.joints.push_back(read_joint(file, root[identifier], identifier, context));
}

// A body identifier written in a joint, sensor or actuator, as a body index.
int find_body(const std::map<std::string, int>& body_by_identifier, const std::string& identifier,
              const SourceLocation& where, const std::string& role, const std::string& owner) {
  auto found = body_by_identifier.find(identifier);
  if (found == body_by_identifier.end())
    fail(where, role + " '" + identifier + "' of " + owner +
                    " is not a loaded body; list it in a 'bodies' header of a loaded file");
  return found->second;
}

}  // namespace

void load_adf_files_into(const std::vector<std::string>& paths, Model& model) {
  Unresolved pending;
  std::map<std::string, int> body_by_identifier;
  for (const std::string& path : paths) {
    YAML::Node root = parse_file(path, "an ADF file (a map with 'bodies' and 'joints' lists)");
    try {
      load_file(path, root, model, pending, body_by_identifier);
    } catch (const YAML::Exception& error) {
      // A key looked up inside a scalar or a list, for instance.
      throw Error(path + ":" + std::to_string(error.mark.line + 1) + ":" +
                  std::to_string(error.mark.column + 1) + ": error: " + error.msg);
    }
  }

  for (PendingJoint& joint : pending.joints) {
    const std::string& owner = joint.spec.identifier;
    joint.spec.parent =
        find_body(body_by_identifier, joint.parent, joint.parent_at, "parent", owner);
    joint.spec.child = find_body(body_by_identifier, joint.child, joint.child_at, "child", owner);
    if (joint.spec.parent == joint.spec.child)
      fail(joint.child_at, joint.spec.identifier + " joins '" + joint.child +
                               "' to itself; parent and child must differ");
    model.joints.push_back(joint.spec);
  }
  for (const PendingParent& item : pending.parents) {
    const std::string& owner =
        item.sensor ? model.sensors[item.index].identifier : model.actuators[item.index].identifier;
    const int body = find_body(body_by_identifier, item.parent, item.parent_at, "parent", owner);
    (item.sensor ? model.sensors[item.index].parent : model.actuators[item.index].parent) = body;
  }
  compute_lineage(model);
}

Model load_adf_files(const std::vector<std::string>& paths) {
  Model model;
  load_adf_files_into(paths, model);
  return model;
}

}  // namespace afhub::physics
