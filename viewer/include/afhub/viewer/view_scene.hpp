// The viewer's copy of a scene description (shm_layout/scene.hpp): what the page
// draws, as JSON, and the mesh files it may serve (those the scene lists, within the
// model folders it lists: mesh_file.hpp).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "afhub/shm_layout/scene.hpp"
#include "afhub/shm_layout/soft_body.hpp"

namespace afhub::viewer {

struct ViewScene {
  std::uint32_t generation = 0;       // counts the descriptions the viewer read: a new one, reload
  std::vector<std::string> channels;  // per body, its state channel
  // /mesh/N's files, absolute paths: per body its first mesh (or ""), then the
  // scene's further mesh parts
  std::vector<std::string> meshes;
  std::vector<std::string> model_folders;  // the folders meshes may be served from
  std::vector<std::string> soft_channels;  // per soft body, its channel
  std::string json;                        // what /scene.json serves
};

// Copies a checked description (check_payload passed) into a ViewScene, with per
// soft body its checked faces (`soft_faces[i]`, nullptr: not read yet, none listed).
ViewScene view_scene_of(const SceneDescription& scene, std::uint32_t generation,
                        const std::vector<const SoftBodyMesh*>& soft_faces = {});

// What the viewer serves before it has read a scene: a scene of nothing, generation 0
// (a page opened before the physics runs loads it, then the scene with the next
// generation).
ViewScene no_scene();

}  // namespace afhub::viewer
