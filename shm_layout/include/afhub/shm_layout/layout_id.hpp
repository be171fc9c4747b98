// kLayoutId: a fingerprint of every payload's layout, stamped into each header.
// It mixes the size, alignment and every field offset of every payload, so any
// layout change gives another id and a process built from other sources is
// refused instead of misread. Adding a field means adding its offset below.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <type_traits>

#include "afhub/shm_layout/bench_sample.hpp"
#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/catalog.hpp"
#include "afhub/shm_layout/device.hpp"
#include "afhub/shm_layout/device_tape.hpp"
#include "afhub/shm_layout/health.hpp"
#include "afhub/shm_layout/loop_stats.hpp"
#include "afhub/shm_layout/scene.hpp"
#include "afhub/shm_layout/scene_poses.hpp"
#include "afhub/shm_layout/slot.hpp"
#include "afhub/shm_layout/slot_block.hpp"
#include "afhub/shm_layout/soft_body.hpp"
#include "afhub/shm_layout/step_tape.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub {

// Bump when a field's meaning changes without its layout changing.
inline constexpr std::uint64_t kLayoutRevision = 3;  // 3: the step tape holds states packed

namespace layout_detail {

constexpr std::uint64_t fnv1a(std::uint64_t hash, std::uint64_t value) {
  for (int byte = 0; byte < 8; ++byte) {
    hash ^= (value >> (8 * byte)) & 0xffU;
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

constexpr std::uint64_t mix(std::initializer_list<std::size_t> values) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (std::size_t v : values) hash = fnv1a(hash, v);
  return hash;
}

template <class T>
constexpr bool is_shm_payload = std::is_trivially_copyable_v<T>&& std::is_standard_layout_v<T>;

}  // namespace layout_detail

#define AFHUB_OFF(type, field) offsetof(type, field)
inline constexpr std::uint64_t kLayoutId = layout_detail::mix({
    kLayoutRevision,
    kMaxJointsPerBody,
    kMaxBodies,
    kMaxSensorRaysPerBody,
    kMaxActuatorsPerBody,
    kMaxWorldObjects,
    kMaxHealthProcesses,
    kMaxMempools,
    kMaxCatalogJointNames,
    kMaxCatalogJointRefs,
    sizeof(PayloadHeader),
    AFHUB_OFF(PayloadHeader, kind),
    AFHUB_OFF(PayloadHeader, publisher_pid),
    AFHUB_OFF(PayloadHeader, sequence),
    AFHUB_OFF(PayloadHeader, sim_step),
    AFHUB_OFF(PayloadHeader, sim_time_s),
    AFHUB_OFF(PayloadHeader, publish_stamp_ns),
    sizeof(Vec3),
    sizeof(Quaternion),
    sizeof(Pose),
    sizeof(Twist),
    sizeof(Wrench),
    sizeof(BodyState),
    alignof(BodyState),
    AFHUB_OFF(BodyState, pose),
    AFHUB_OFF(BodyState, twist),
    AFHUB_OFF(BodyState, wrench),
    AFHUB_OFF(BodyState, contact_wrench),
    AFHUB_OFF(BodyState, contact_count),
    AFHUB_OFF(BodyState, mass_kg),
    AFHUB_OFF(BodyState, principal_inertia_kgm2),
    AFHUB_OFF(BodyState, joint_count),
    AFHUB_OFF(BodyState, joints),
    sizeof(JointSample),
    offsetof(JointSample, position),
    offsetof(JointSample, velocity),
    offsetof(JointSample, effort),
    AFHUB_OFF(BodyState, step_due_ns),
    AFHUB_OFF(BodyState, command_answered_step),
    AFHUB_OFF(BodyState, sensor_ray_count),
    AFHUB_OFF(BodyState, sensor_distances_m),
    AFHUB_OFF(BodyState, sensor_ranges_m),
    AFHUB_OFF(BodyState, commanded_steps),
    AFHUB_OFF(BodyState, answered_steps),
    AFHUB_OFF(BodyState, refused_commands),
    AFHUB_OFF(BodyState, refused_command_pid),
    AFHUB_OFF(BodyState, refusal_reason),
    kRefusalReasonSize,
    sizeof(BodyCommand),
    alignof(BodyCommand),
    AFHUB_OFF(BodyCommand, cartesian_type),
    AFHUB_OFF(BodyCommand, lockstep),
    AFHUB_OFF(BodyCommand, joint_count),
    AFHUB_OFF(BodyCommand, pose),
    AFHUB_OFF(BodyCommand, wrench),
    AFHUB_OFF(BodyCommand, twist),
    AFHUB_OFF(BodyCommand, joints),
    sizeof(JointCommand),
    offsetof(JointCommand, value),
    offsetof(JointCommand, type),
    AFHUB_OFF(BodyCommand, actuator_count),
    AFHUB_OFF(BodyCommand, actuate),
    sizeof(DeviceSpec),
    AFHUB_OFF(DeviceSpec, serial),
    AFHUB_OFF(DeviceSpec, max_force_n),
    AFHUB_OFF(DeviceSpec, max_torque_nm),
    AFHUB_OFF(DeviceSpec, max_gripper_force_n),
    AFHUB_OFF(DeviceSpec, max_stiffness_npm),
    AFHUB_OFF(DeviceSpec, workspace_radius_m),
    AFHUB_OFF(DeviceSpec, sensed),
    AFHUB_OFF(DeviceSpec, actuated),
    AFHUB_OFF(DeviceSpec, button_count),
    sizeof(DeviceState),
    AFHUB_OFF(DeviceState, spec),
    AFHUB_OFF(DeviceState, pose),
    AFHUB_OFF(DeviceState, velocity),
    AFHUB_OFF(DeviceState, gripper_angle_rad),
    AFHUB_OFF(DeviceState, buttons),
    AFHUB_OFF(DeviceState, gate),
    AFHUB_OFF(DeviceState, applied),
    AFHUB_OFF(DeviceState, applied_gripper_force_n),
    AFHUB_OFF(DeviceState, command_sequence),
    AFHUB_OFF(DeviceState, command_stamp_ns),
    sizeof(DeviceCommand),
    AFHUB_OFF(DeviceCommand, wrench),
    AFHUB_OFF(DeviceCommand, gripper_force_n),
    AFHUB_OFF(DeviceCommand, enable),
    sizeof(WorldState),
    AFHUB_OFF(WorldState, wall_time_s),
    AFHUB_OFF(WorldState, achieved_rate_hz),
    AFHUB_OFF(WorldState, step_due_ns),
    AFHUB_OFF(WorldState, step_period_ns),
    AFHUB_OFF(WorldState, body_count),
    AFHUB_OFF(WorldState, paused),
    AFHUB_OFF(WorldState, lockstep),
    AFHUB_OFF(WorldState, pause_held),
    AFHUB_OFF(WorldState, paused_by_pid),
    AFHUB_OFF(WorldState, lockstep_clients),
    AFHUB_OFF(WorldState, late_answers),
    AFHUB_OFF(WorldState, dropped_clients),
    AFHUB_OFF(WorldState, commanded_steps),
    AFHUB_OFF(WorldState, answered_steps),
    AFHUB_OFF(WorldState, rejected_commands),
    AFHUB_OFF(WorldState, watchdog_expiries),
    AFHUB_OFF(WorldState, stale_commands),
    AFHUB_OFF(WorldState, nan_recoveries),
    AFHUB_OFF(WorldState, last_nan_step),
    AFHUB_OFF(WorldState, last_nan_body),
    AFHUB_OFF(WorldState, light_count),
    AFHUB_OFF(WorldState, camera_count),
    AFHUB_OFF(WorldState, lights),
    AFHUB_OFF(WorldState, cameras),
    sizeof(WorldObjectPose),
    sizeof(WorldCommand),
    AFHUB_OFF(WorldCommand, action),
    AFHUB_OFF(WorldCommand, step_count),
    AFHUB_OFF(WorldCommand, hold_ms),
    AFHUB_OFF(WorldCommand, valid_ms),
    sizeof(BodyInfo),
    AFHUB_OFF(BodyInfo, channel),
    AFHUB_OFF(BodyInfo, owner),
    AFHUB_OFF(BodyInfo, owner_pid),
    AFHUB_OFF(BodyInfo, joint_count),
    AFHUB_OFF(BodyInfo, publish_rate_hz),
    AFHUB_OFF(BodyInfo, first_joint_ref),
    AFHUB_OFF(BodyInfo, kind),
    AFHUB_OFF(BodyInfo, sensor_ray_count),
    AFHUB_OFF(BodyInfo, actuator_count),
    AFHUB_OFF(BodyInfo, child_count),
    AFHUB_OFF(BodyInfo, parent_count),
    sizeof(JointName),
    sizeof(BodyList),
    AFHUB_OFF(BodyList, body_count),
    AFHUB_OFF(BodyList, joint_name_count),
    AFHUB_OFF(BodyList, joint_ref_count),
    AFHUB_OFF(BodyList, bodies),
    sizeof(Health),
    AFHUB_OFF(Health, hub_uptime_s),
    AFHUB_OFF(Health, process_count),
    AFHUB_OFF(Health, mempool_count),
    AFHUB_OFF(Health, body_count),
    AFHUB_OFF(Health, free_publisher_ports),
    AFHUB_OFF(Health, free_subscriber_ports),
    AFHUB_OFF(Health, processes),
    AFHUB_OFF(Health, mempools),
    sizeof(ProcessEntry),
    sizeof(MempoolUsage),
    AFHUB_OFF(MempoolUsage, chunk_payload_bytes),
    sizeof(LoopStats),
    AFHUB_OFF(LoopStats, name),
    AFHUB_OFF(LoopStats, body),
    AFHUB_OFF(LoopStats, period_s),
    AFHUB_OFF(LoopStats, rate_hz),
    AFHUB_OFF(LoopStats, cycles),
    AFHUB_OFF(LoopStats, overruns),
    AFHUB_OFF(LoopStats, late_commands),
    AFHUB_OFF(LoopStats, wake_latency),
    AFHUB_OFF(LoopStats, compute),
    AFHUB_OFF(LoopStats, realtime),
    AFHUB_OFF(LoopStats, memory_locked),
    AFHUB_OFF(LoopStats, lockstep),
    AFHUB_OFF(LoopStats, cpu),
    AFHUB_OFF(LoopStats, cpu_wake_latency_us),
    sizeof(DurationPercentiles),
    sizeof(BenchSample),
    AFHUB_OFF(BenchSample, send_ns),
    AFHUB_OFF(BenchSample, peer_receive_ns),
    kMaxSceneBodies,
    kMaxSceneShapesPerBody,
    kScenePathBufferSize,
    sizeof(SceneShape),
    AFHUB_OFF(SceneShape, kind),
    AFHUB_OFF(SceneShape, axis),
    AFHUB_OFF(SceneShape, size_m),
    AFHUB_OFF(SceneShape, offset),
    sizeof(SceneBody),
    AFHUB_OFF(SceneBody, channel),
    AFHUB_OFF(SceneBody, mesh),
    AFHUB_OFF(SceneBody, mesh_offset),
    AFHUB_OFF(SceneBody, mesh_scale),
    AFHUB_OFF(SceneBody, color_rgba),
    AFHUB_OFF(SceneBody, pose),
    AFHUB_OFF(SceneBody, publishes),
    AFHUB_OFF(SceneBody, shape_count),
    AFHUB_OFF(SceneBody, shapes),
    sizeof(SceneView),
    AFHUB_OFF(SceneView, name),
    AFHUB_OFF(SceneView, key),
    AFHUB_OFF(SceneView, position_m),
    AFHUB_OFF(SceneView, direction),
    AFHUB_OFF(SceneView, up),
    sizeof(SceneDescription),
    AFHUB_OFF(SceneDescription, light_count),
    AFHUB_OFF(SceneDescription, camera_count),
    AFHUB_OFF(SceneDescription, lights),
    AFHUB_OFF(SceneDescription, cameras),
    AFHUB_OFF(SceneDescription, body_count),
    AFHUB_OFF(SceneDescription, bodies),
    kMaxSceneSoftBodies,
    sizeof(SceneSoftBody),
    AFHUB_OFF(SceneDescription, soft_body_count),
    AFHUB_OFF(SceneDescription, soft_bodies),
    kMaxSceneModelFolders,
    kMaxSceneMeshParts,
    sizeof(SceneMeshPart),
    AFHUB_OFF(SceneMeshPart, body),
    AFHUB_OFF(SceneMeshPart, offset),
    AFHUB_OFF(SceneMeshPart, scale),
    AFHUB_OFF(SceneMeshPart, mesh),
    AFHUB_OFF(SceneDescription, mesh_part_count),
    AFHUB_OFF(SceneDescription, mesh_parts),
    AFHUB_OFF(SceneDescription, model_folder_count),
    AFHUB_OFF(SceneDescription, model_folders),
    kMaxSceneModelFiles,
    AFHUB_OFF(SceneDescription, model_file_count),
    AFHUB_OFF(SceneDescription, model_files),
    kMaxSoftBodyNodes,
    kMaxSoftBodyFaces,
    sizeof(SoftBodyMesh),
    AFHUB_OFF(SoftBodyMesh, node_count),
    AFHUB_OFF(SoftBodyMesh, face_count),
    AFHUB_OFF(SoftBodyMesh, nodes),
    AFHUB_OFF(SoftBodyMesh, faces),
    kMaxSceneJointValues,
    sizeof(ScenePose),
    AFHUB_OFF(ScenePose, position_m),
    AFHUB_OFF(ScenePose, orientation_xyzw),
    AFHUB_OFF(ScenePose, first_joint),
    AFHUB_OFF(ScenePose, joint_count),
    sizeof(ScenePoses),
    AFHUB_OFF(ScenePoses, body_count),
    AFHUB_OFF(ScenePoses, joint_value_count),
    AFHUB_OFF(ScenePoses, bodies),
    sizeof(StepTape),
    AFHUB_OFF(StepTape, part),
    AFHUB_OFF(StepTape, last_part),
    AFHUB_OFF(StepTape, first_entry),
    AFHUB_OFF(StepTape, entry_count),
    AFHUB_OFF(StepTape, data_bytes),
    AFHUB_OFF(StepTape, data),
    sizeof(StepTapeEntry),
    AFHUB_OFF(StepTapeEntry, payload_bytes),
    AFHUB_OFF(StepTapeEntry, kind),
    sizeof(StepTapeRing),
    kStepTapeRingParts,
    AFHUB_OFF(StepTapeRing, written),
    AFHUB_OFF(StepTapeRing, parts),
    sizeof(TapeRingId),
    AFHUB_OFF(TapeRingId, made_ns),
    AFHUB_OFF(TapeRingId, part_count),
    sizeof(TapeRingPart<StepTape>),
    AFHUB_OFF(TapeRingPart<StepTape>, tape),
    sizeof(DeviceTape),
    AFHUB_OFF(DeviceTape, command),
    AFHUB_OFF(DeviceTape, has_command),
    sizeof(DeviceTapeRing),
    kDeviceTapeRingParts,
    AFHUB_OFF(DeviceTapeRing, written),
    AFHUB_OFF(DeviceTapeRing, parts),
    sizeof(SlotControl),
    AFHUB_OFF(SlotControl, sleeping),
    AFHUB_OFF(SlotControl, stamp_ns),
    AFHUB_OFF(SlotControl, payload_bytes),
    sizeof(SlotBlockHeader),
    AFHUB_OFF(SlotBlockHeader, layout_id),
    AFHUB_OFF(SlotBlockHeader, kind),
    AFHUB_OFF(SlotBlockHeader, writer_pid),
    AFHUB_OFF(SlotBlockHeader, entry_count),
    AFHUB_OFF(SlotBlockHeader, entry_bytes),
    AFHUB_OFF(SlotBlockHeader, claimed),
    AFHUB_OFF(SlotBlockHeader, closed),
    sizeof(SlotEntryHeader),
    AFHUB_OFF(SlotEntryHeader, readers),
    AFHUB_OFF(SlotEntryHeader, service),
    AFHUB_OFF(SlotEntryHeader, instance),
    AFHUB_OFF(SlotEntryHeader, event),
    kSlotBlockMagic,
});
#undef AFHUB_OFF

// Shared memory is mapped at another address in every process: payloads must be
// plain bytes, with no pointers, no owning members and no virtual functions.
static_assert(layout_detail::is_shm_payload<BodyState>);
static_assert(layout_detail::is_shm_payload<BodyCommand>);
static_assert(layout_detail::is_shm_payload<WorldState>);
static_assert(layout_detail::is_shm_payload<WorldCommand>);
static_assert(layout_detail::is_shm_payload<BodyList>);
static_assert(layout_detail::is_shm_payload<Health>);
static_assert(layout_detail::is_shm_payload<LoopStats>);
static_assert(layout_detail::is_shm_payload<BenchSample>);
static_assert(layout_detail::is_shm_payload<DeviceState>);
static_assert(layout_detail::is_shm_payload<DeviceCommand>);
static_assert(layout_detail::is_shm_payload<SceneDescription>);
static_assert(layout_detail::is_shm_payload<SoftBodyMesh>);
static_assert(layout_detail::is_shm_payload<ScenePoses>);
static_assert(layout_detail::is_shm_payload<StepTape>);
static_assert(layout_detail::is_shm_payload<DeviceTape>);

}  // namespace afhub
