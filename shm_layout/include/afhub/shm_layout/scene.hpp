// SceneDescription: what a viewer needs to draw a world, published once by the
// physics (keep-last history, as the directory), on {"afhub", <world instance>,
// "scene"}: per body its channel, visual meshes (absolute paths, placed and scaled)
// or primitive shapes, and colour; the world's lights and cameras; the folders of the models
// it loaded (a viewer serves no mesh outside them). Poses travel in the
// body states, the world state and the viewer's pose feed (scene_poses.hpp), never
// here. Loaned at its real size,
// scene_description_bytes(body_count): only the first body_count entries exist.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "afhub/shm_layout/geometry.hpp"
#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

// An absolute mesh path. Linux allows 4096, but model trees are shallow: 512 keeps a
// body entry near 1 KB. A longer path is left out of the scene (the body is then
// drawn as a marker) and said once by the physics.
inline constexpr std::size_t kScenePathBufferSize = 512;

// Model folders a scene lists: one per model tree (a model file and its meshes) the
// physics loaded; `afhub run` of a launch file loads a few.
inline constexpr std::size_t kMaxSceneModelFolders = 16;

// Model files a scene lists (ADF, URDF, the world file), for a recording to name what
// was simulated: a launch file's scene loads a few; a robot of many files, a few tens.
inline constexpr std::size_t kMaxSceneModelFiles = 32;

// Visual meshes beyond each body's first (a URDF link with several <visual> elements),
// in all: robots with such links have a few; 64 entries cost 37 KB in every scene
// chunk. Further ones are left out of the scene and said once by the physics.
inline constexpr std::size_t kMaxSceneMeshParts = 64;

// Primitive shapes drawn for one body (a compound shape lists several); AMBF's
// models use one, generated ones a few.
inline constexpr std::size_t kMaxSceneShapesPerBody = 8;

enum class SceneShapeKind : std::uint32_t {
  kBox = 0,
  kSphere = 1,
  kCylinder = 2,
  kCapsule = 3,
  kCone = 4,
  kPlane = 5
};

struct SceneShape {
  SceneShapeKind kind{SceneShapeKind::kBox};
  std::uint32_t axis{2};  // 0, 1, 2 = X, Y, Z: cylinder, capsule, cone
  Vec3 size_m;            // box: full sizes; others: x = radius, y = height
  Pose offset;            // in the body's mesh frame
};

struct SceneBody {
  std::array<char, kChannelNameBufferSize> channel{};  // its state's channel; NUL-terminated
  std::array<char, kScenePathBufferSize> mesh{};       // absolute path, or "" for shapes
  Pose mesh_offset;                                    // where `mesh` sits in the body's frame
  Vec3 mesh_scale{1.0, 1.0, 1.0};                      // per axis (its shapes' sizes are in metres)
  std::array<float, 4> color_rgba{0.7F, 0.7F, 0.7F, 1.0F};
  Pose pose;  // where it was loaded: the pose of a body that publishes no state (passive)
  std::uint8_t publishes{1};  // 0: passive, drawn at `pose`
  std::uint8_t reserved[3]{};
  std::uint32_t shape_count{0};  // entries [0, shape_count) of `shapes`
  std::array<SceneShape, kMaxSceneShapesPerBody> shapes{};
};

// A further visual mesh of body `body`, drawn with it as its first mesh is.
struct SceneMeshPart {
  std::uint32_t body{0};  // an index into SceneDescription.bodies
  std::uint32_t reserved{0};
  Pose offset;                                    // in the body's frame
  Vec3 scale{1.0, 1.0, 1.0};                      // per axis
  std::array<char, kScenePathBufferSize> mesh{};  // absolute path, NUL-terminated
};

// A world file's light or camera: where it is and where it looks, in the world
// frame when the scene was published (one carried by a body moves with it: its live
// pose is in the world state).
struct SceneView {
  std::array<char, kChannelNameBufferSize> name{};
  // Its block key in the world file ("camera1"): AMBF's input devices pair cameras
  // by it. Cut at the buffer like the name.
  std::array<char, kChannelNameBufferSize> key{};
  Vec3 position_m;
  Vec3 direction;  // where it looks or shines, a unit vector
  Vec3 up{0.0, 0.0, 1.0};
};

// A soft body: its surface travels on its own channels (shm_layout/soft_body.hpp).
struct SceneSoftBody {
  std::array<char, kChannelNameBufferSize> channel{};  // NUL-terminated
};

struct SceneDescription {
  static constexpr PayloadKind kKind = PayloadKind::kSceneDescription;
  PayloadHeader header;
  std::uint32_t light_count{0};
  std::uint32_t camera_count{0};
  std::array<SceneView, kMaxWorldObjects> lights{};
  std::array<SceneView, kMaxWorldObjects> cameras{};
  std::uint32_t soft_body_count{0};  // entries [0, soft_body_count) of `soft_bodies`
  std::uint32_t reserved_soft{0};
  std::array<SceneSoftBody, kMaxSceneSoftBodies> soft_bodies{};
  // Absolute folders, NUL-terminated: each the deepest folder holding both a loaded
  // model file and a mesh it names. Entries [0, model_folder_count) exist.
  std::uint32_t model_folder_count{0};
  std::uint32_t reserved_folders{0};
  std::array<std::array<char, kScenePathBufferSize>, kMaxSceneModelFolders> model_folders{};
  // The model files loaded, absolute, NUL-terminated: entries [0, model_file_count).
  std::uint32_t model_file_count{0};
  std::uint32_t reserved_files{0};
  std::array<std::array<char, kScenePathBufferSize>, kMaxSceneModelFiles> model_files{};
  std::uint32_t mesh_part_count{0};  // entries [0, mesh_part_count) of `mesh_parts`
  std::uint32_t reserved_parts{0};
  std::array<SceneMeshPart, kMaxSceneMeshParts> mesh_parts{};
  std::uint32_t body_count{0};
  std::uint32_t reserved{0};
  std::array<SceneBody, kMaxSceneBodies> bodies{};  // last: sized by body_count
};

// Bytes of a SceneDescription holding `bodies` bodies: what is loaned and published.
constexpr std::size_t scene_description_bytes(std::size_t bodies) {
  return offsetof(SceneDescription, bodies) + bodies * sizeof(SceneBody);
}

}  // namespace afhub
