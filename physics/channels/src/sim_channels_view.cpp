// The simulation's channels for viewers: the scene description, the soft bodies'
// faces and nodes, and the scene's poses at the viewer rate.
#include <algorithm>
#include <cstdio>

#include "afhub/physics/sim_channels.hpp"
#include "afhub/shm_layout/error.hpp"
#include "scene_description.hpp"

namespace afhub::physics {

void SimChannels::publish_scene() {
  const std::size_t count = scene_body_count(sim_.model());
  SceneDescription* scene = scene_.loan(scene_description_bytes(count));
  if (!scene)
    throw Error("no shared memory for the scene description of " + std::to_string(count) +
                " bodies; see `afhub status` for the mempools");
  std::vector<std::string> warnings;
  fill_scene(sim_, *scene, warnings);
  for (const std::string& warning : warnings)
    std::fprintf(stderr, "afhub run: %s\n", warning.c_str());
  scene_.publish(scene);
}

void SimChannels::publish_soft_faces() {
  for (SoftSurface& surface : soft_surfaces_) {
    const auto faces = sim_.soft_body_faces(surface.index);  // within bounds: checked at load
    SoftBodyMesh* mesh = surface.faces->loan(soft_body_mesh_bytes(faces.size()));
    if (!mesh)
      throw Error("no shared memory for the faces of soft body '" +
                  sim_.model().soft_bodies[surface.index].channel +
                  "'; see `afhub status` for the mempools");
    mesh->node_count = static_cast<std::uint32_t>(sim_.soft_body_node_count(surface.index));
    mesh->face_count = static_cast<std::uint32_t>(faces.size());
    sim_.read_soft_body_nodes(surface.index, mesh->nodes.data());
    std::copy(faces.begin(), faces.end(), mesh->faces.begin());
    surface.faces->publish(mesh);
  }
}

void SimChannels::publish_view(std::int64_t now_ns) noexcept {
  if (now_ns < view_next_ns_) return;
  view_next_ns_ = now_ns + static_cast<std::int64_t>(1e9 / kViewerRateHz);
  publish_scene_poses();
  publish_soft_nodes();
}

void SimChannels::publish_soft_nodes() noexcept {
  for (SoftSurface& surface : soft_surfaces_) {
    // Kept for a viewer that joins later: published once without readers, then for them.
    if (surface.nodes_published && !surface.nodes->raw().has_readers()) continue;
    SoftBodyMesh* mesh = surface.nodes->loan(soft_body_mesh_bytes(0));
    if (!mesh) continue;  // shared memory exhausted: skip, never block
    mesh->header.sim_step = sim_.step_count();
    mesh->header.sim_time_s = sim_.time_s();
    mesh->node_count = static_cast<std::uint32_t>(sim_.soft_body_node_count(surface.index));
    sim_.read_soft_body_nodes(surface.index, mesh->nodes.data());
    surface.nodes->publish(mesh);
    surface.nodes_published = true;
  }
}

void SimChannels::publish_scene_poses() noexcept {
  if (scene_poses_published_ && !scene_poses_.raw().has_readers()) return;
  const Model& model = sim_.model();
  const auto bodies = static_cast<std::uint32_t>(scene_body_count(model));
  auto* poses = static_cast<ScenePoses*>(
      scene_poses_.raw().loan(scene_poses_bytes(bodies, scene_joint_values_)));
  if (!poses) return;  // shared memory exhausted: skip, never block
  poses->header = PayloadHeader{};
  poses->header.sim_step = sim_.step_count();
  poses->header.sim_time_s = sim_.time_s();
  poses->body_count = bodies;
  float* joint_positions = joint_positions_in(*poses);
  std::uint32_t values = 0;
  for (std::uint32_t b = 0; b < poses->body_count; ++b) {
    const Pose pose = sim_.body_pose(b);
    ScenePose& out = poses->bodies[b];
    out.first_joint = out.joint_count = 0;
    out.position_m = {static_cast<float>(pose.position_m.x), static_cast<float>(pose.position_m.y),
                      static_cast<float>(pose.position_m.z)};
    out.orientation_xyzw = {
        static_cast<float>(pose.orientation.x), static_cast<float>(pose.orientation.y),
        static_cast<float>(pose.orientation.z), static_cast<float>(pose.orientation.w)};
    if (model.bodies[b].passive) continue;  // no state: no joints to show
    const std::vector<int>& below = model.descendant_joints[b];
    const auto count = static_cast<std::uint32_t>(std::min(below.size(), kBodyJointCapacity));
    if (values + count > scene_joint_values_) continue;  // past the feed's capacity: said once
    out.first_joint = values;
    out.joint_count = count;
    for (std::uint32_t j = 0; j < count; ++j)
      joint_positions[values++] = static_cast<float>(sim_.joint_position(below[j]));
  }
  poses->joint_value_count = values;
  scene_poses_.publish(poses);
  scene_poses_published_ = true;
}

}  // namespace afhub::physics
