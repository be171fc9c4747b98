// ADF writer (see adf_writer.hpp). Shapes are written as compound lists with their
// offsets (a single ADF `collision shape` would sit at the inertial offset), and
// sizes divided by the body's scale, which the loader applies to shapes too.
#include "afhub/physics/adf_writer.hpp"

#include <cstdio>
#include <sstream>

namespace afhub::physics {
namespace {

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

std::string quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string xyz(const Vec3& v) {
  return "{x: " + number(v.x) + ", y: " + number(v.y) + ", z: " + number(v.z) + "}";
}

std::string placement(const Placement& p) {
  return "{position: " + xyz(p.position_m) + ", orientation: {r: " + number(p.rpy_rad.x) +
         ", p: " + number(p.rpy_rad.y) + ", y: " + number(p.rpy_rad.z) + "}}";
}

std::string shape(const ShapeSpec& s, double scale) {
  std::string geometry;
  switch (s.kind) {
    case ShapeKind::kBox:
      return "{shape: BOX, geometry: {x: " + number(s.box_size_m.x / scale) +
             ", y: " + number(s.box_size_m.y / scale) + ", z: " + number(s.box_size_m.z / scale) +
             "}, offset: " +
             placement({{s.offset.position_m.x / scale, s.offset.position_m.y / scale,
                         s.offset.position_m.z / scale},
                        s.offset.rpy_rad}) +
             "}";
    case ShapeKind::kSphere:
      geometry = "{radius: " + number(s.radius_m / scale) + "}";
      break;
    default:
      geometry = "{radius: " + number(s.radius_m / scale) +
                 ", height: " + number(s.height_m / scale) +
                 ", axis: " + std::string(1, "XYZ"[s.axis]) + "}";
      break;
  }
  const char* kind = s.kind == ShapeKind::kSphere     ? "SPHERE"
                     : s.kind == ShapeKind::kCylinder ? "CYLINDER"
                     : s.kind == ShapeKind::kCapsule  ? "CAPSULE"
                                                      : "CONE";
  return std::string("{shape: ") + kind + ", geometry: " + geometry + ", offset: " +
         placement({{s.offset.position_m.x / scale, s.offset.position_m.y / scale,
                     s.offset.position_m.z / scale},
                    s.offset.rpy_rad}) +
         "}";
}

void write_shapes(std::ostream& out, const char* key, const std::vector<ShapeSpec>& shapes,
                  double scale) {
  if (shapes.empty()) return;
  out << "  " << key << ":\n";
  for (const ShapeSpec& s : shapes) out << "  - " << shape(s, scale) << "\n";
}

// afhub's extension (body_reader.cpp): meshes placed in the body's frame, in metres,
// each with its scale.
void write_placed_meshes(std::ostream& out, const char* key,
                         const std::vector<PlacedMesh>& meshes) {
  if (meshes.empty()) return;
  out << "  " << key << ":\n";
  for (const PlacedMesh& m : meshes)
    out << "  - {mesh: " << quoted(m.path) << ", offset: " << placement(m.offset)
        << ", scale: " << xyz(m.scale) << "}\n";
}

void write_body(std::ostream& out, const BodySpec& body) {
  out << quoted(body.identifier) << ":\n";
  out << "  name: " << quoted(body.name) << "\n";
  out << "  mass: " << number(body.mass_kg) << "\n";
  if (body.inertia_kgm2)
    out << "  inertia: {ix: " << number(body.inertia_kgm2->x)
        << ", iy: " << number(body.inertia_kgm2->y) << ", iz: " << number(body.inertia_kgm2->z)
        << "}\n";
  out << "  location: " << placement(body.location) << "\n";
  if (body.inertial_offset)
    out << "  inertial offset: " << placement(*body.inertial_offset) << "\n";
  if (body.scale != 1.0) out << "  scale: " << number(body.scale) << "\n";
  if (!body.visual_mesh.empty()) out << "  mesh: " << quoted(body.visual_mesh) << "\n";
  write_placed_meshes(out, "visual meshes", body.visual_mesh_parts);
  write_shapes(out, "compound shape", body.visual_shapes, body.scale);
  if (!body.collision_mesh.empty()) {
    out << "  collision mesh: " << quoted(body.collision_mesh) << "\n";
    out << "  collision mesh type: TRIMESH\n";
  }
  write_placed_meshes(out, "collision meshes", body.collision_mesh_parts);
  write_shapes(out, "compound collision shape", body.collision_shapes, body.scale);
  if (body.color_rgba) {
    const auto& c = *body.color_rgba;
    out << "  color rgba: {r: " << number(c[0]) << ", g: " << number(c[1])
        << ", b: " << number(c[2]) << ", a: " << number(c[3]) << "}\n";
  }
}

void write_joint(std::ostream& out, const Model& model, const JointSpec& joint) {
  out << quoted(joint.identifier) << ":\n";
  out << "  name: " << quoted(joint.name) << "\n";
  out << "  parent: " << quoted(model.bodies[joint.parent].identifier) << "\n";
  out << "  child: " << quoted(model.bodies[joint.child].identifier) << "\n";
  out << "  parent pivot: " << xyz(joint.parent_pivot_m) << "\n";
  out << "  parent axis: " << xyz(joint.parent_axis) << "\n";
  out << "  child pivot: " << xyz(joint.child_pivot_m) << "\n";
  out << "  child axis: " << xyz(joint.child_axis) << "\n";
  out << "  type: " << joint_type_name(joint.type) << "\n";
  if (joint.limit_low)
    out << "  joint limits: {low: " << number(*joint.limit_low)
        << ", high: " << number(*joint.limit_high) << "}\n";
  if (joint.multi_limits) {
    const SixDofLimits& l = *joint.multi_limits;
    out << "  joint limits:\n    linear: {low: " << xyz(l.linear_low)
        << ", high: " << xyz(l.linear_high) << "}\n    angular: {low: " << xyz(l.angular_low)
        << ", high: " << xyz(l.angular_high) << "}\n";
  }
  // The paper's Algorithm 3: the turn about the axis that makes the joint read zero
  // at the pose the bodies are placed in.
  out << "  offset: " << number(joint.offset_rad) << "\n";
  if (joint.damping != 0.0) out << "  damping: " << number(joint.damping) << "\n";
  out << "  max motor impulse: " << number(joint.max_motor_impulse) << "\n";
  if (joint.max_velocity)  // afhub's key (AMBF has none)
    out << "  max velocity: " << number(*joint.max_velocity) << "\n";
}

}  // namespace

std::string adf_text(const Model& model, std::vector<std::string>& lost) {
  std::ostringstream out;
  out << "# Written by `afhub convert`. Mesh paths are absolute.\n";
  out << "adf version: '1.0'\n";
  if (!model.bodies.empty()) {
    const BodySpec& first = model.bodies.front();
    const std::string& qualified = first.qualified_identifier;
    out << "namespace: " << quoted(qualified.substr(0, qualified.size() - first.identifier.size()))
        << "\n";
  }
  out << "bodies:\n";
  for (const BodySpec& body : model.bodies) out << "- " << quoted(body.identifier) << "\n";
  if (!model.joints.empty()) out << "joints:\n";
  for (const JointSpec& joint : model.joints) out << "- " << quoted(joint.identifier) << "\n";
  for (const BodySpec& body : model.bodies) write_body(out, body);
  for (const JointSpec& joint : model.joints) {
    write_joint(out, model, joint);
    if (joint.mimic)
      lost.push_back("joint '" + joint.name + "' mimics '" + model.joints[joint.mimic->joint].name +
                     "': ADF has no mimic joints, so it is written as an ordinary joint");
  }
  return out.str();
}

}  // namespace afhub::physics
