// Validation of received payloads (see payload_check.hpp).
#include "afhub/shm_layout/payload_check.hpp"

#include <cmath>
#include <cstring>

#include "afhub/shm_layout/layout_id.hpp"
#include "afhub/shm_layout/loop_stats.hpp"
#include "afhub/shm_layout/packed_body_state.hpp"

namespace afhub {
namespace {

std::size_t fixed_size_of(PayloadKind kind) noexcept {
  switch (kind) {
    case PayloadKind::kBodyState:
      return body_state_bytes(0);
    case PayloadKind::kBodyCommand:
      return body_command_bytes(0);
    case PayloadKind::kWorldState:
      return sizeof(WorldState);
    case PayloadKind::kWorldCommand:
      return sizeof(WorldCommand);
    case PayloadKind::kHealth:
      return sizeof(Health);
    case PayloadKind::kLoopStats:
      return sizeof(LoopStats);
    case PayloadKind::kBenchSample:
    case PayloadKind::kBenchSlot:
      return sizeof(BenchSample);
    case PayloadKind::kDeviceState:
      return sizeof(DeviceState);
    case PayloadKind::kDeviceCommand:
      return sizeof(DeviceCommand);
    case PayloadKind::kBodyDirectory:
    case PayloadKind::kCatalog:
      return body_list_bytes(0);
    case PayloadKind::kSceneDescription:
      return scene_description_bytes(0);
    case PayloadKind::kSoftBodyMesh:
      return soft_body_mesh_bytes(0);
    case PayloadKind::kScenePoses:
      return scene_poses_bytes(0);  // an empty scene's
    case PayloadKind::kStepTape:
      return offsetof(StepTape, data);  // read at its used size
  }
  return 0;
}

// A body list's joint names and refs: their counts within capacity and the chunk,
// every body's refs within the list's, every ref a name. nullptr when all hold.
const char* body_list_problem(const BodyList& list, std::size_t bytes) noexcept {
  if (list.body_count > kMaxBodies || bytes < body_list_bytes(list.body_count))
    return "BodyList.body_count";
  if (list.joint_name_count > kMaxCatalogJointNames ||
      bytes < body_list_bytes(list.body_count, list.joint_name_count))
    return "BodyList.joint_name_count";
  if (list.joint_ref_count > kMaxCatalogJointRefs ||
      bytes < body_list_bytes(list.body_count, list.joint_name_count, list.joint_ref_count))
    return "BodyList.joint_ref_count";
  for (std::uint32_t i = 0; i < list.body_count; ++i) {
    const BodyInfo& body = list.bodies[i];
    if (body.joint_count > kMaxJointsPerBody) return "BodyInfo.joint_count";
    if (body.sensor_ray_count > kMaxSensorRaysPerBody) return "BodyInfo.sensor_ray_count";
    if (body.actuator_count > kMaxActuatorsPerBody) return "BodyInfo.actuator_count";
    if (body.child_count > kMaxModelBodies) return "BodyInfo.child_count";
    if (body.parent_count > 1) return "BodyInfo.parent_count";
    if (body.first_joint_ref + body_ref_count(body) > list.joint_ref_count)
      return "BodyInfo.first_joint_ref";
  }
  const std::uint32_t* refs = joint_refs_in(list);
  for (std::uint32_t r = 0; r < list.joint_ref_count; ++r)
    if (refs[r] >= list.joint_name_count) return "BodyList joint reference";
  return nullptr;
}

// A tape's entries within its data and the chunk, each a channel name and a state, a
// command or a world state within its type's sizes (each is checked as what it is by
// whoever reads it).
const char* step_tape_problem(const StepTape& tape, std::size_t bytes) noexcept {
  if (tape.data_bytes > tape.data.size() || bytes < offsetof(StepTape, data) + tape.data_bytes)
    return "StepTape.data_bytes";
  std::size_t at = 0;
  for (std::uint32_t e = 0; e < tape.entry_count; ++e) {
    StepTapeEntry entry;
    if (tape.data_bytes - at < sizeof entry) return "StepTape.entry_count";
    std::memcpy(&entry, tape.data.data() + at, sizeof entry);
    if (entry.name_bytes == 0 || entry.name_bytes >= kChannelNameBufferSize)
      return "StepTapeEntry.name_bytes";
    std::size_t least = 0, most = 0;
    switch (entry.kind) {
      case PayloadKind::kBodyState:  // packed
        least = packed_body_state_bytes(false, 0, 0), most = sizeof(BodyState);
        break;
      case PayloadKind::kBodyCommand:
        least = body_command_bytes(0), most = sizeof(BodyCommand);
        break;
      case PayloadKind::kWorldState:
        least = most = sizeof(WorldState);
        break;
      default:
        return "StepTapeEntry.kind";
    }
    if (entry.payload_bytes < least || entry.payload_bytes > most)
      return "StepTapeEntry.payload_bytes";
    const std::size_t entry_bytes = step_tape_entry_bytes(entry.name_bytes, entry.payload_bytes);
    if (tape.data_bytes - at < entry_bytes) return "StepTapeEntry.payload_bytes";
    at += entry_bytes;
  }
  return nullptr;
}

template <std::size_t N>
bool terminated(const std::array<char, N>& text) noexcept {
  return std::memchr(text.data(), '\0', N) != nullptr;
}

// A scene's counts within capacity and the chunk, and every name and path
// NUL-terminated (a viewer opens the paths). nullptr when all hold.
const char* scene_problem(const SceneDescription& scene, std::size_t bytes) noexcept {
  if (scene.light_count > kMaxWorldObjects) return "SceneDescription.light_count";
  if (scene.camera_count > kMaxWorldObjects) return "SceneDescription.camera_count";
  for (std::uint32_t i = 0; i < scene.light_count; ++i) {
    if (!terminated(scene.lights[i].name)) return "SceneView.name";
    if (!terminated(scene.lights[i].key)) return "SceneView.key";
  }
  for (std::uint32_t i = 0; i < scene.camera_count; ++i) {
    if (!terminated(scene.cameras[i].name)) return "SceneView.name";
    if (!terminated(scene.cameras[i].key)) return "SceneView.key";
  }
  if (scene.soft_body_count > kMaxSceneSoftBodies) return "SceneDescription.soft_body_count";
  for (std::uint32_t i = 0; i < scene.soft_body_count; ++i)
    if (!terminated(scene.soft_bodies[i].channel)) return "SceneSoftBody.channel";
  if (scene.model_folder_count > kMaxSceneModelFolders)
    return "SceneDescription.model_folder_count";
  for (std::uint32_t i = 0; i < scene.model_folder_count; ++i)
    if (!terminated(scene.model_folders[i])) return "SceneDescription.model_folders";
  if (scene.model_file_count > kMaxSceneModelFiles) return "SceneDescription.model_file_count";
  for (std::uint32_t i = 0; i < scene.model_file_count; ++i)
    if (!terminated(scene.model_files[i])) return "SceneDescription.model_files";
  if (scene.body_count > kMaxSceneBodies || bytes < scene_description_bytes(scene.body_count))
    return "SceneDescription.body_count";
  for (std::uint32_t b = 0; b < scene.body_count; ++b) {
    const SceneBody& body = scene.bodies[b];
    if (!terminated(body.channel)) return "SceneBody.channel";
    if (!terminated(body.mesh)) return "SceneBody.mesh";
    if (body.shape_count > kMaxSceneShapesPerBody) return "SceneBody.shape_count";
  }
  if (scene.mesh_part_count > kMaxSceneMeshParts) return "SceneDescription.mesh_part_count";
  for (std::uint32_t p = 0; p < scene.mesh_part_count; ++p) {
    if (scene.mesh_parts[p].body >= scene.body_count) return "SceneMeshPart.body";
    if (!terminated(scene.mesh_parts[p].mesh)) return "SceneMeshPart.mesh";
  }
  return nullptr;
}

// A soft body's counts within capacity and the chunk, and every face's nodes among
// its nodes (a viewer indexes them). nullptr when all hold.
const char* soft_body_problem(const SoftBodyMesh& mesh, std::size_t bytes) noexcept {
  if (mesh.node_count > kMaxSoftBodyNodes) return "SoftBodyMesh.node_count";
  if (mesh.face_count > kMaxSoftBodyFaces || bytes < soft_body_mesh_bytes(mesh.face_count))
    return "SoftBodyMesh.face_count";
  for (std::uint32_t f = 0; f < mesh.face_count; ++f)
    for (std::uint32_t node : mesh.faces[f])
      if (node >= mesh.node_count) return "SoftBodyMesh.faces";
  return nullptr;
}

const char* scene_poses_problem(const ScenePoses& poses, std::size_t bytes) noexcept {
  if (poses.body_count > kMaxSceneBodies || bytes < scene_poses_bytes(poses.body_count))
    return "ScenePoses.body_count";
  if (poses.joint_value_count > kMaxSceneJointValues ||
      bytes < scene_poses_bytes(poses.body_count, poses.joint_value_count))
    return "ScenePoses.joint_value_count";
  for (std::uint32_t b = 0; b < poses.body_count; ++b) {
    const ScenePose& body = poses.bodies[b];
    if (body.joint_count > kMaxJointsPerBody ||
        std::uint64_t{body.first_joint} + body.joint_count > poses.joint_value_count)
      return "ScenePose.first_joint";
  }
  return nullptr;
}

// The first count beyond its capacity or the chunk's `bytes` (or a body state's
// unterminated refusal reason), named; nullptr when every count fits. The chunk holds
// at least the kind's fixed size.
const char* count_beyond_capacity(const char* at, std::size_t bytes, PayloadKind kind) noexcept {
  switch (kind) {
    case PayloadKind::kBodyState: {
      const auto* state = reinterpret_cast<const BodyState*>(at);
      if (state->joint_count > kMaxJointsPerBody || bytes < body_state_bytes(state->joint_count))
        return "BodyState.joint_count";
      if (state->sensor_ray_count > kMaxSensorRaysPerBody) return "BodyState.sensor_ray_count";
      if (!terminated(state->refusal_reason)) return "BodyState.refusal_reason";
      return nullptr;
    }
    case PayloadKind::kBodyCommand: {
      const auto* command = reinterpret_cast<const BodyCommand*>(at);
      if (command->joint_count > kMaxJointsPerBody ||
          bytes < body_command_bytes(command->joint_count))
        return "BodyCommand.joint_count";
      if (command->actuator_count > kMaxActuatorsPerBody) return "BodyCommand.actuator_count";
      return nullptr;
    }
    case PayloadKind::kWorldState: {
      const auto* world = reinterpret_cast<const WorldState*>(at);
      if (world->light_count > kMaxWorldObjects) return "WorldState.light_count";
      if (world->camera_count > kMaxWorldObjects) return "WorldState.camera_count";
      return nullptr;
    }
    case PayloadKind::kBodyDirectory:
    case PayloadKind::kCatalog:
      return body_list_problem(*reinterpret_cast<const BodyList*>(at), bytes);
    case PayloadKind::kHealth: {
      const auto* health = reinterpret_cast<const Health*>(at);
      if (health->process_count > kMaxHealthProcesses) return "Health.process_count";
      if (health->mempool_count > kMaxMempools) return "Health.mempool_count";
      return nullptr;
    }
    case PayloadKind::kDeviceState: {
      const auto* state = reinterpret_cast<const DeviceState*>(at);
      if (state->gate > ForceGate::kStopping) return "DeviceState.gate";
      return device_reading_problem(state->pose, state->velocity, state->gripper_angle_rad);
    }
    case PayloadKind::kDeviceCommand: {
      const auto* command = reinterpret_cast<const DeviceCommand*>(at);
      const Wrench& w = command->wrench;
      for (double v : {w.force_n.x, w.force_n.y, w.force_n.z})
        if (!std::isfinite(v)) return "DeviceCommand.wrench.force_n";
      for (double v : {w.torque_nm.x, w.torque_nm.y, w.torque_nm.z})
        if (!std::isfinite(v)) return "DeviceCommand.wrench.torque_nm";
      if (!std::isfinite(command->gripper_force_n)) return "DeviceCommand.gripper_force_n";
      return nullptr;
    }
    case PayloadKind::kSceneDescription:
      return scene_problem(*reinterpret_cast<const SceneDescription*>(at), bytes);
    case PayloadKind::kSoftBodyMesh:
      return soft_body_problem(*reinterpret_cast<const SoftBodyMesh*>(at), bytes);
    case PayloadKind::kScenePoses:
      return scene_poses_problem(*reinterpret_cast<const ScenePoses*>(at), bytes);
    case PayloadKind::kStepTape:
      return step_tape_problem(*reinterpret_cast<const StepTape*>(at), bytes);
    case PayloadKind::kWorldCommand: {
      const auto* command = reinterpret_cast<const WorldCommand*>(at);
      if (command->action > WorldAction::kRelease) return "WorldCommand.action";
      if (command->hold_ms > kMaxPauseHoldMs ||
          (command->hold_ms != 0 && command->header.publisher_pid == 0))
        return "WorldCommand.hold_ms";  // a hold needs a holder to renew it
      if (command->valid_ms > kMaxWorldCommandValidMs) return "WorldCommand.valid_ms";
      if (command->action == WorldAction::kStep &&
          (command->step_count == 0 || command->step_count > kMaxWorldStepsPerCommand))
        return "WorldCommand.step_count";
      return nullptr;
    }
    case PayloadKind::kLoopStats:
    case PayloadKind::kBenchSample:
    case PayloadKind::kBenchSlot:
      return nullptr;
  }
  return nullptr;
}

PayloadError fail(PayloadError error, const char* what, const char** field) noexcept {
  if (field) *field = what;
  return error;
}

}  // namespace

// Readers (teleop's law, renderings) take the pose as numbers: a NaN would stay in a
// law's anchor for good.
const char* device_reading_problem(const Pose& pose, const Twist& velocity,
                                   double gripper_angle_rad) noexcept {
  for (double v : {pose.position_m.x, pose.position_m.y, pose.position_m.z, pose.orientation.x,
                   pose.orientation.y, pose.orientation.z, pose.orientation.w})
    if (!std::isfinite(v)) return "DeviceState.pose";
  for (double v : {velocity.linear_mps.x, velocity.linear_mps.y, velocity.linear_mps.z,
                   velocity.angular_radps.x, velocity.angular_radps.y, velocity.angular_radps.z})
    if (!std::isfinite(v)) return "DeviceState.velocity";
  if (!std::isfinite(gripper_angle_rad)) return "DeviceState.gripper_angle_rad";
  return nullptr;
}

PayloadError check_payload(const void* data, std::size_t bytes, PayloadKind expected,
                           const char** field) noexcept {
  if (field) *field = "";
  if (bytes < sizeof(PayloadHeader)) return fail(PayloadError::kTooSmall, "PayloadHeader", field);
  PayloadHeader header;
  std::memcpy(&header, data, sizeof header);
  if (header.layout_id != kLayoutId)
    return fail(PayloadError::kForeignLayout, "PayloadHeader.layout_id", field);
  if (header.kind != expected) return fail(PayloadError::kWrongKind, "PayloadHeader.kind", field);
  if (bytes < fixed_size_of(expected)) return fail(PayloadError::kTooSmall, "chunk size", field);
  const auto* at = static_cast<const char*>(data);
  if (const char* count = count_beyond_capacity(at, bytes, expected))
    return fail(PayloadError::kCountTooLarge, count, field);
  return PayloadError::kNone;
}

PayloadError check_packed_body_state(const void* data, std::size_t bytes,
                                     const char** field) noexcept {
  if (field) *field = "";
  if (bytes < kPackedReasonAt) return fail(PayloadError::kTooSmall, "chunk size", field);
  const auto* at = static_cast<const std::uint8_t*>(data);
  PayloadHeader header;
  std::memcpy(&header, at, sizeof header);
  if (header.layout_id != kLayoutId)
    return fail(PayloadError::kForeignLayout, "PayloadHeader.layout_id", field);
  if (header.kind != PayloadKind::kBodyState)
    return fail(PayloadError::kWrongKind, "PayloadHeader.kind", field);
  std::uint32_t rays = 0, joints = 0;
  std::memcpy(&joints, at + offsetof(BodyState, joint_count), sizeof joints);
  std::memcpy(&rays, at + offsetof(BodyState, sensor_ray_count), sizeof rays);
  if (joints > kMaxJointsPerBody)
    return fail(PayloadError::kCountTooLarge, "BodyState.joint_count", field);
  if (rays > kMaxSensorRaysPerBody)
    return fail(PayloadError::kCountTooLarge, "BodyState.sensor_ray_count", field);
  if (bytes == packed_body_state_bytes(true, rays, joints)) {
    if (!std::memchr(at + kPackedReasonAt, '\0', kRefusalReasonSize))
      return fail(PayloadError::kCountTooLarge, "BodyState.refusal_reason", field);
    return PayloadError::kNone;
  }
  if (bytes != packed_body_state_bytes(false, rays, joints))
    return fail(PayloadError::kCountTooLarge, "BodyState.joint_count", field);
  return PayloadError::kNone;
}

const char* describe(PayloadError error) noexcept {
  switch (error) {
    case PayloadError::kNone:
      return "valid";
    case PayloadError::kTooSmall:
      return "the chunk is smaller than the payload it claims to be; the writer was built "
             "from other afhub sources: rebuild it from the same sources as this process";
    case PayloadError::kForeignLayout:
      return "the payload layout id differs from this build's: the writer was built from other "
             "afhub sources; rebuild both from the same sources";
    case PayloadError::kWrongKind:
      return "the channel carries another payload type than expected; check the channel name "
             "and that the writer uses the afhub client library";
    case PayloadError::kCountTooLarge:
      return "a field of the payload is out of its range (a count beyond its capacity, a value "
             "no reader takes, or a number that is not finite); the writer is faulty or foreign";
  }
  return "unknown payload error";
}

}  // namespace afhub
