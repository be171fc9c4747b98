// The scene description (see scene_description.hpp).
#include "scene_description.hpp"

#include <algorithm>
#include <cstring>
#include <filesystem>

namespace afhub::physics {
namespace {

template <std::size_t N>
bool copy_text(const std::string& text, std::array<char, N>& out) {
  if (text.size() >= N) return false;
  std::memcpy(out.data(), text.c_str(), text.size() + 1);
  return true;
}

SceneShape to_scene_shape(const ShapeSpec& shape) {
  SceneShape out;
  out.kind = static_cast<SceneShapeKind>(shape.kind);
  out.axis = static_cast<std::uint32_t>(shape.axis);
  out.offset = {shape.offset.position_m, rpy_to_quaternion(shape.offset.rpy_rad)};
  switch (shape.kind) {
    case ShapeKind::kBox:
      out.size_m = shape.box_size_m;
      break;
    case ShapeKind::kPlane:
      // A plane: its normal, and its point nearest the body's origin.
      out.size_m = shape.plane_normal;
      out.offset.position_m = {shape.plane_normal.x * shape.plane_offset_m,
                               shape.plane_normal.y * shape.plane_offset_m,
                               shape.plane_normal.z * shape.plane_offset_m};
      break;
    default:
      out.size_m = {shape.radius_m, shape.height_m, 0.0};
      break;
  }
  return out;
}

// `v` turned by the unit quaternion `q`.
Vec3 rotate(const Quaternion& q, const Vec3& v) {
  // t = 2 q.xyz x v; v' = v + w t + q.xyz x t
  const Vec3 t{2 * (q.y * v.z - q.z * v.y), 2 * (q.z * v.x - q.x * v.z),
               2 * (q.x * v.y - q.y * v.x)};
  return {v.x + q.w * t.x + (q.y * t.z - q.z * t.y), v.y + q.w * t.y + (q.z * t.x - q.x * t.z),
          v.z + q.w * t.z + (q.x * t.y - q.y * t.x)};
}

// A light or camera where it is now, in the world frame (carried by its parent body
// when it has one): it looks along its x axis, with z up.
template <std::size_t N>
void copy_cut(const std::string& text, std::array<char, N>& out) {
  const std::size_t length = std::min(text.size(), N - 1);
  std::memcpy(out.data(), text.data(), length);
  out[length] = '\0';
}

void fill_view(const WorldObjectSpec& spec, const Pose& pose, SceneView& view) {
  // Names are channel-sized in the model already; a longer one (or key) is cut.
  copy_cut(spec.name, view.name);
  copy_cut(spec.key, view.key);
  view.position_m = pose.position_m;
  view.direction = rotate(pose.orientation, {1.0, 0.0, 0.0});
  view.up = rotate(pose.orientation, {0.0, 0.0, 1.0});
}

// The body's visual meshes: its first in its SceneBody, the others in the scene's
// mesh parts while they last.
void add_meshes(const BodySpec& spec, std::uint32_t index, SceneDescription& scene,
                std::vector<std::string>& warnings) {
  std::vector<PlacedMesh> meshes;
  if (!spec.visual_mesh.empty())
    meshes.push_back({spec.visual_mesh, {}, uniform_scale(spec.scale)});
  meshes.insert(meshes.end(), spec.visual_mesh_parts.begin(), spec.visual_mesh_parts.end());
  SceneBody& body = scene.bodies[index];
  for (const PlacedMesh& mesh : meshes) {
    std::error_code ignored;
    const std::string path = std::filesystem::absolute(mesh.path, ignored).string();
    const Pose offset{mesh.offset.position_m, rpy_to_quaternion(mesh.offset.rpy_rad)};
    if (path.size() >= kScenePathBufferSize) {
      warnings.push_back(spec.where.str() + ": warning: '" + spec.name + "': mesh path " + path +
                         " is longer than a viewer takes (" +
                         std::to_string(kScenePathBufferSize - 1) + " characters); not drawn");
    } else if (body.mesh[0] == '\0') {
      copy_text(path, body.mesh);
      body.mesh_offset = offset;
      body.mesh_scale = mesh.scale;
    } else if (scene.mesh_part_count == kMaxSceneMeshParts) {
      warnings.push_back(spec.where.str() + ": warning: '" + spec.name + "': a viewer draws " +
                         std::to_string(kMaxSceneMeshParts) +
                         " further visual meshes in a scene; mesh " + path + " is not drawn");
    } else {
      SceneMeshPart& part = scene.mesh_parts[scene.mesh_part_count++];
      part.body = index;
      part.offset = offset;
      part.scale = mesh.scale;
      copy_text(path, part.mesh);
    }
  }
}

// The deepest folder holding both `model_file` and `mesh`: the model's tree, where a
// viewer may serve its meshes from (AMBF's models keep theirs in ../../../meshes).
std::filesystem::path model_folder(const std::string& model_file, const std::string& mesh) {
  namespace fs = std::filesystem;
  std::error_code ignored;
  const fs::path a = fs::weakly_canonical(fs::absolute(model_file, ignored), ignored).parent_path();
  const fs::path b = fs::path(mesh).parent_path();
  fs::path common;
  for (auto i = a.begin(), j = b.begin(); i != a.end() && j != b.end() && *i == *j; ++i, ++j)
    common /= *i;
  return common;
}

// Names the files the model came from (model_files), as many as the scene holds.
void fill_model_files(const Model& model, SceneDescription& scene,
                      std::vector<std::string>& warnings) {
  scene.model_file_count = 0;
  for (const std::string& file : model_files(model)) {
    if (scene.model_file_count == kMaxSceneModelFiles ||
        !copy_text(file, scene.model_files[scene.model_file_count])) {
      warnings.push_back("a recording does not name " + file + ": the scene description lists " +
                         std::to_string(kMaxSceneModelFiles) + " model files of at most " +
                         std::to_string(kScenePathBufferSize - 1) + " characters");
      continue;
    }
    ++scene.model_file_count;
  }
}

// Lists the model folders of the bodies' meshes, each once (none inside another).
void fill_model_folders(const Model& model, SceneDescription& scene,
                        std::vector<std::string>& warnings) {
  std::vector<std::string> folders;
  for (std::size_t b = 0; b < scene.body_count; ++b)
    if (scene.bodies[b].mesh[0] != '\0')
      folders.push_back(model_folder(model.bodies[b].where.file, scene.bodies[b].mesh.data()));
  for (std::size_t p = 0; p < scene.mesh_part_count; ++p) {
    const SceneMeshPart& part = scene.mesh_parts[p];
    folders.push_back(model_folder(model.bodies[part.body].where.file, part.mesh.data()));
  }
  std::sort(folders.begin(), folders.end());
  std::vector<std::string> listed;
  scene.model_folder_count = 0;
  for (const std::string& folder : folders) {
    const bool inside =
        !listed.empty() && (folder == listed.back() || folder.starts_with(listed.back() + "/") ||
                            listed.back() == "/");
    if (!inside) listed.push_back(folder);
  }
  for (const std::string& folder : listed) {
    if (scene.model_folder_count == kMaxSceneModelFolders ||
        !copy_text(folder, scene.model_folders[scene.model_folder_count])) {
      warnings.push_back("a viewer serves no mesh under " + folder + ": the scene description " +
                         "lists " + std::to_string(kMaxSceneModelFolders) +
                         " model folders of at most " + std::to_string(kScenePathBufferSize - 1) +
                         " characters");
      continue;
    }
    ++scene.model_folder_count;
  }
}

}  // namespace

static_assert(static_cast<int>(ShapeKind::kPlane) == static_cast<int>(SceneShapeKind::kPlane));
static_assert(static_cast<int>(ShapeKind::kCone) == static_cast<int>(SceneShapeKind::kCone));

std::size_t scene_body_count(const Model& model) {
  return std::min(model.bodies.size(), kMaxSceneBodies);
}

void fill_scene(const Simulation& sim, SceneDescription& scene,
                std::vector<std::string>& warnings) {
  const Model& model = sim.model();
  scene.light_count =
      static_cast<std::uint32_t>(std::min(model.world.lights.size(), kMaxWorldObjects));
  scene.camera_count =
      static_cast<std::uint32_t>(std::min(model.world.cameras.size(), kMaxWorldObjects));
  for (std::uint32_t i = 0; i < scene.light_count; ++i)
    fill_view(model.world.lights[i], sim.light_pose(i), scene.lights[i]);
  for (std::uint32_t i = 0; i < scene.camera_count; ++i)
    fill_view(model.world.cameras[i], sim.camera_pose(i), scene.cameras[i]);
  const std::size_t soft = std::min(model.soft_bodies.size(), kMaxSceneSoftBodies);
  if (soft < model.soft_bodies.size())
    warnings.push_back("the scene description holds " + std::to_string(kMaxSceneSoftBodies) +
                       " soft bodies; a viewer does not draw the other " +
                       std::to_string(model.soft_bodies.size() - soft));
  scene.soft_body_count = static_cast<std::uint32_t>(soft);
  for (std::size_t s = 0; s < soft; ++s)
    copy_text(model.soft_bodies[s].channel, scene.soft_bodies[s].channel);  // fits: checked
  const std::size_t count = scene_body_count(model);
  if (count < model.bodies.size())
    warnings.push_back("the scene description holds " + std::to_string(kMaxSceneBodies) +
                       " bodies; a viewer does not draw the other " +
                       std::to_string(model.bodies.size() - count));
  scene.body_count = static_cast<std::uint32_t>(count);
  scene.mesh_part_count = 0;
  for (std::size_t b = 0; b < count; ++b) {
    const BodySpec& spec = model.bodies[b];
    SceneBody& body = scene.bodies[b];
    body = SceneBody{};
    copy_text(spec.channel, body.channel);  // checked at load to fit a channel
    add_meshes(spec, static_cast<std::uint32_t>(b), scene, warnings);
    if (spec.color_rgba)
      for (int c = 0; c < 4; ++c) body.color_rgba[c] = static_cast<float>((*spec.color_rgba)[c]);
    body.pose = sim.body_pose(b);
    body.publishes = spec.passive ? 0 : 1;
    const std::size_t shapes = std::min(spec.visual_shapes.size(), kMaxSceneShapesPerBody);
    if (shapes < spec.visual_shapes.size())
      warnings.push_back(spec.where.str() + ": warning: '" + spec.name + "': a viewer draws " +
                         std::to_string(shapes) + " of its " +
                         std::to_string(spec.visual_shapes.size()) + " shapes");
    body.shape_count = static_cast<std::uint32_t>(shapes);
    for (std::size_t s = 0; s < shapes; ++s) body.shapes[s] = to_scene_shape(spec.visual_shapes[s]);
  }
  fill_model_folders(model, scene, warnings);
  fill_model_files(model, scene, warnings);
}

}  // namespace afhub::physics
