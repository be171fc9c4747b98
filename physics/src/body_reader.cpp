// ADF rigid bodies (BODY blocks): mass and inertia, placement, material, visual and
// collision geometry (meshes or primitive shapes), the Cartesian controller, color.
#include <algorithm>
#include <cmath>
#include <map>

#include "adf_blocks.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "body_scope.hpp"

namespace afhub::physics::adf {
namespace {

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
                                         "visual meshes",
                                         "collision meshes",
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

// `visual meshes` and `collision meshes`, an afhub extension AMBF ignores:
// [{mesh: FILE, offset: {position, orientation}, scale: {x, y, z}}], each placed in the
// body's frame in metres (its offset not scaled) and scaled per axis (by default as the
// body's `scale`), as a URDF link's several <visual> or <collision> elements are;
// `afhub convert` writes them.
std::vector<PlacedMesh> read_placed_meshes(const FileReader& file, const YAML::Node& list,
                                           const std::string& folder, double body_scale,
                                           const std::string& what) {
  if (!list.IsSequence() || list.size() == 0)
    fail(file.at(list), "'" + what + "' must be a non-empty list of {mesh: FILE, offset: " +
                            "{position: {x, y, z}, orientation: {r, p, y}}, scale: {x, y, z}}");
  std::vector<PlacedMesh> meshes;
  for (const auto& entry : list) {
    file.require_map(entry, what + " entry", "{mesh: part.stl, offset: {position: ...}}");
    YAML::Node mesh = entry["mesh"];
    if (!mesh) fail(file.at(entry), "'" + what + "' entry needs 'mesh'");
    PlacedMesh placed{
        resolve_mesh(file, mesh, folder, what + " mesh"), {}, uniform_scale(body_scale)};
    if (YAML::Node offset = entry["offset"]) placed.offset = file.placement(offset, "offset");
    if (YAML::Node scale = entry["scale"]) {
      placed.scale = file.vec3(scale, what + " scale");
      for (double axis : {placed.scale.x, placed.scale.y, placed.scale.z})
        if (!(std::abs(axis) > 0) || std::abs(axis) > kMaxScale)
          fail(file.at(scale), "each axis of a '" + what + "' scale must be other than 0 and " +
                                   "within -" + yaml::number_text(kMaxScale) + " to " +
                                   yaml::number_text(kMaxScale) + " (negative: mirrored)");
    }
    meshes.push_back(std::move(placed));
  }
  return meshes;
}

// A color component: 0 to 1 (a color file's named colors are 0 to 255).
void optional_component(const FileReader& file, const YAML::Node& map, const char* key, double& out,
                        const std::string& what) {
  if (YAML::Node value = map[key]) {
    out = file.non_negative(value, what);
    if (out > 1.0)
      fail(file.at(value),
           "'" + what + "' is " + value.Scalar() + "; a component is from 0 to 1 (255 is 1)");
  }
}

// Colors are kept for a future viewer: `color rgba`, `color components` or a named `color`.
void read_color(const FileReader& file, const YAML::Node& block, BodySpec& body) {
  if (YAML::Node rgba = block["color rgba"]) {
    file.require_map(rgba, "color rgba", "{r: 1, g: 0, b: 0, a: 1}");
    std::array<double, 4> color{0.0, 0.0, 0.0, 1.0};
    const char* keys[4] = {"r", "g", "b", "a"};
    for (int i = 0; i < 4; ++i)
      optional_component(file, rgba, keys[i], color[i], std::string("color rgba.") + keys[i]);
    body.color_rgba = color;
  } else if (YAML::Node components = block["color components"]) {
    file.require_map(components, "color components", "{diffuse: {r, g, b}, transparency: 1}");
    std::array<double, 4> color{0.5, 0.5, 0.5, 1.0};
    if (YAML::Node diffuse = components["diffuse"]) {
      file.require_map(diffuse, "color components.diffuse", "{r: 1, g: 0, b: 0}");
      const char* keys[3] = {"r", "g", "b"};
      for (int i = 0; i < 3; ++i)
        optional_component(file, diffuse, keys[i], color[i],
                           std::string("color components.diffuse.") + keys[i]);
    }
    optional_component(file, components, "transparency", color[3], "color components.transparency");
    body.color_rgba = color;
  }
  if (YAML::Node name = block["color"]) body.color_name = file.text(name, "color");
}

}  // namespace

BodySpec read_body(const FileReader& file, const YAML::Node& block, const std::string& identifier,
                   const FileContext& context) {
  BodySpec body;
  read_block_head(file, block, identifier, kBodyKeys, "body", body);
  body.file_index = context.file_index;
  std::erase(body.name, ' ');
  const std::string name_space = block_namespace(file, block, context);
  body.channel = body_channel_name(name_space, body.name);
  body.qualified_identifier = qualified_identifier(name_space, identifier);
  if (auto problem = channel_name_problem(body.channel); !problem.empty())
    fail(body.where, problem);

  YAML::Node mass = block["mass"];
  if (!mass)
    fail(body.where, "'" + identifier +
                         "' has no 'mass' (AMBF would silently use 1 kg); give 'mass: 0' for a "
                         "static body or its mass in kg");
  body.mass_kg = file.non_negative(mass, "mass");
  if (body.mass_kg > kMaxMassKg)
    fail(file.at(mass), "'mass' is " + mass.Scalar() + " kg, beyond the bound of " +
                            yaml::number_text(kMaxMassKg) + " kg for a model");
  if (body.mass_kg > 0.0 && body.mass_kg < kMinMovingMassKg)
    fail(file.at(mass), "'mass' is " + mass.Scalar() + " kg, below the " +
                            yaml::number_text(kMinMovingMassKg) +
                            " kg a moving body needs (Bullet divides by it); give 'mass: 0' "
                            "for a static body");
  if (YAML::Node inertia = block["inertia"]) {
    Vec3 value = file.vec3(inertia, "inertia", "ix", "iy", "iz");
    if (value.x < 0 || value.y < 0 || value.z < 0)
      fail(file.at(inertia), "'inertia' components must not be negative");
    if (!possible_principal_inertias(value))
      file.warn(inertia, "'inertia' (" + yaml::number_text(value.x) + ", " +
                             yaml::number_text(value.y) + ", " + yaml::number_text(value.z) +
                             ") has one component larger than the other two together, which no "
                             "rigid body has; check the values and their order");
    if (body.mass_kg > 0.0 && (value.x == 0.0 || value.y == 0.0 || value.z == 0.0))
      file.warn(inertia,
                "'inertia' has a zero component: Bullet takes it as infinite, so the body cannot "
                "turn about that axis; give it, or leave 'inertia' out to have it computed from "
                "the collision mesh");
    body.inertia_kgm2 = value;
  }
  if (YAML::Node offset = block["inertial offset"])
    body.inertial_offset = file.placement(offset, "inertial offset");
  if (YAML::Node location = block["location"]) body.location = file.placement(location, "location");
  if (YAML::Node scale = block["scale"]) {
    body.scale = file.number(scale, "scale");
    if (body.scale <= 0) fail(file.at(scale), "'scale' must be positive, got " + scale.Scalar());
    if (body.scale > kMaxScale)
      fail(file.at(scale), "'scale' is " + scale.Scalar() + ", beyond the bound of " +
                               yaml::number_text(kMaxScale) + " for a model");
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
  if (YAML::Node margin = block["collision margin"]) {
    file.non_negative(margin, "collision margin");
    body.collision_margin = file.bounded(margin, "collision margin", kMaxLengthM, "m");
  }
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
    body.gravity_mps2 = file.gravity(gravity);
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

  if (YAML::Node list = block["visual meshes"])
    body.visual_mesh_parts = read_placed_meshes(file, list, high, body.scale, "visual meshes");
  if (YAML::Node list = block["collision meshes"])
    body.collision_mesh_parts = read_placed_meshes(file, list, low, body.scale, "collision meshes");

  scale_shapes(body.visual_shapes, body.scale);
  scale_shapes(body.collision_shapes, body.scale);
  if (YAML::Node controller = block["controller"]) {
    file.require_map(controller, "controller", "{linear: {P, I, D}, angular: {P, I, D}}");
    if (YAML::Node linear = controller["linear"]) {
      body.linear_controller = read_pid(file, linear, "controller.linear");
      body.linear_output = ControllerOutput::kForce;
    }
    if (YAML::Node angular = controller["angular"]) {
      body.angular_controller = read_pid(file, angular, "controller.angular");
      body.angular_output = ControllerOutput::kForce;
    }
  }
  // As AMBF, only with gains: a FORCE output on the velocity preset (P 10, no D) would be
  // an undamped spring.
  if (YAML::Node output = block["controller output type"]) {
    const ControllerOutput type = read_output_type(file, output);
    if (block["controller"])
      body.linear_output = body.angular_output = type;
    else
      file.warn(output,
                "'controller output type' is ignored without a 'controller' block (as in AMBF): "
                "the body keeps its velocity controller (P 10, no D); give gains to choose FORCE");
  }
  for (const auto& [pid, output, what] :
       {std::tuple{body.linear_controller, body.linear_output, "controller.linear"},
        std::tuple{body.angular_controller, body.angular_output, "controller.angular"}})
    if (output == ControllerOutput::kVelocity && pid.d >= 1.0)
      file.warn(block["controller"] ? block["controller"] : block,
                std::string(what) + " D " + yaml::number_text(pid.d) +
                    " with VELOCITY output: the D term acts on the velocity the "
                    "controller itself sets, and a pose command diverges from D 1; "
                    "give D below 1, or `controller output type: FORCE`");
  read_color(file, block, body);
  return body;
}

}  // namespace afhub::physics::adf
