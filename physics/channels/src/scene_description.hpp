// The scene description a viewer draws from (see shm_layout/scene.hpp), filled from
// the model once, before the loop.
#pragma once

#include <string>
#include <vector>

#include "afhub/physics/simulation.hpp"
#include "afhub/shm_layout/scene.hpp"

namespace afhub::physics {

// How many bodies fill_scene() describes: every body (passive ones too), at most
// kMaxSceneBodies.
std::size_t scene_body_count(const Model& model);

// Fills `scene`, loaned for scene_body_count(model) bodies, from the model and the
// bodies' poses now. What cannot be described (a body past kMaxSceneBodies, a mesh
// path too long, shapes past kMaxSceneShapesPerBody) is left out and said in
// `warnings`.
void fill_scene(const Simulation& sim, SceneDescription& scene, std::vector<std::string>& warnings);

}  // namespace afhub::physics
