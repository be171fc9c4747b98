// The viewer's scene (see view_scene.hpp).
#include "afhub/viewer/view_scene.hpp"

#include <filesystem>
#include <memory>

#include "afhub/hub/json_writer.hpp"

namespace afhub::viewer {
namespace {

void vec3(JsonWriter& json, const Vec3& v) {
  json.begin_array().value(v.x).value(v.y).value(v.z).end_array();
}

void pose(JsonWriter& json, const Pose& p) {
  json.key("position");
  vec3(json, p.position_m);
  const Quaternion& q = p.orientation;
  json.key("orientation").begin_array().value(q.x).value(q.y).value(q.z).value(q.w).end_array();
}

void views(JsonWriter& json, const char* name, const std::array<SceneView, kMaxWorldObjects>& list,
           std::uint32_t count) {
  json.key(name).begin_array();
  for (std::uint32_t i = 0; i < count; ++i) {
    const SceneView& view = list[i];
    json.begin_object().key("name").value(view.name.data()).key("key").value(view.key.data());
    json.key("position");
    vec3(json, view.position_m);
    json.key("direction");
    vec3(json, view.direction);
    json.key("up");
    vec3(json, view.up);
    json.end_object();
  }
  json.end_array();
}

const char* shape_name(SceneShapeKind kind) {
  switch (kind) {
    case SceneShapeKind::kBox:
      return "box";
    case SceneShapeKind::kSphere:
      return "sphere";
    case SceneShapeKind::kCylinder:
      return "cylinder";
    case SceneShapeKind::kCapsule:
      return "capsule";
    case SceneShapeKind::kCone:
      return "cone";
    case SceneShapeKind::kPlane:
      return "plane";
  }
  return "box";
}

// One of a body's meshes: what /mesh/`index` serves. The page learns a mesh's
// format and name, never its path on this machine.
void mesh(JsonWriter& json, std::size_t index, const char* path, const Pose& offset,
          const Vec3& scale) {
  const std::filesystem::path file(path);
  json.begin_object().key("index").value(static_cast<unsigned long long>(index));
  json.key("mesh").value(file.filename().string());
  json.key("format").value(file.extension().string());
  pose(json, offset);
  json.key("scale");
  vec3(json, scale);
  json.end_object();
}

}  // namespace

ViewScene view_scene_of(const SceneDescription& scene, std::uint32_t generation,
                        const std::vector<const SoftBodyMesh*>& soft_faces) {
  ViewScene out;
  out.generation = generation;
  JsonWriter json;
  json.begin_object().key("generation").value(static_cast<unsigned long long>(out.generation));
  views(json, "lights", scene.lights, scene.light_count);
  views(json, "cameras", scene.cameras, scene.camera_count);
  json.key("bodies").begin_array();
  // /mesh/N: body N's first mesh, then mesh part N - body_count.
  for (std::uint32_t b = 0; b < scene.body_count; ++b)
    out.meshes.emplace_back(scene.bodies[b].mesh.data());
  for (std::uint32_t p = 0; p < scene.mesh_part_count; ++p)
    out.meshes.emplace_back(scene.mesh_parts[p].mesh.data());
  for (std::uint32_t b = 0; b < scene.body_count; ++b) {
    const SceneBody& body = scene.bodies[b];
    out.channels.emplace_back(body.channel.data());
    json.begin_object().key("channel").value(body.channel.data());
    json.key("meshes").begin_array();
    if (body.mesh[0] != '\0') mesh(json, b, body.mesh.data(), body.mesh_offset, body.mesh_scale);
    for (std::uint32_t p = 0; p < scene.mesh_part_count; ++p)
      if (const SceneMeshPart& part = scene.mesh_parts[p]; part.body == b)
        mesh(json, scene.body_count + p, part.mesh.data(), part.offset, part.scale);
    json.end_array();
    json.key("color").numbers(body.color_rgba, 4);
    json.key("publishes").value(body.publishes != 0);
    pose(json, body.pose);
    json.key("shapes").begin_array();
    for (std::uint32_t s = 0; s < body.shape_count; ++s) {
      const SceneShape& shape = body.shapes[s];
      json.begin_object().key("kind").value(shape_name(shape.kind));
      json.key("axis").value(static_cast<long long>(shape.axis)).key("size");
      vec3(json, shape.size_m);
      pose(json, shape.offset);
      json.end_object();
    }
    json.end_array().end_object();
  }
  json.end_array();
  for (std::uint32_t f = 0; f < scene.model_folder_count; ++f)
    out.model_folders.emplace_back(scene.model_folders[f].data());
  json.key("soft_bodies").begin_array();
  for (std::uint32_t s = 0; s < scene.soft_body_count; ++s) {
    out.soft_channels.emplace_back(scene.soft_bodies[s].channel.data());
    const SoftBodyMesh* faces = s < soft_faces.size() ? soft_faces[s] : nullptr;
    json.begin_object().key("channel").value(scene.soft_bodies[s].channel.data());
    json.key("nodes").value(static_cast<unsigned long long>(faces ? faces->node_count : 0));
    json.key("faces").begin_array();
    for (std::uint32_t f = 0; faces && f < faces->face_count; ++f)
      for (std::uint32_t node : faces->faces[f]) json.value(static_cast<unsigned long long>(node));
    json.end_array().end_object();
  }
  json.end_array().end_object();
  out.json = json.str();
  return out;
}

ViewScene no_scene() {
  return view_scene_of(*std::make_unique<SceneDescription>(), 0);  // its counts all 0
}

}  // namespace afhub::viewer
