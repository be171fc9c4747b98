// ADF primitive shapes: `shape` + `geometry` (BOX, SPHERE, CYLINDER, CAPSULE, CONE,
// PLANE), compound shapes as lists of them, and `scale` applied to their sizes.
#include <map>

#include "adf_blocks.hpp"

namespace afhub::physics::adf {
namespace {

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

}  // namespace

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
    positive(file, value, what + "." + key);
    return file.length(value, what + "." + key);
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
          geometry["offset"] ? file.length(geometry["offset"], what + ".offset") : 0.0;
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

}  // namespace afhub::physics::adf
