#include "recorded_payloads.hpp"

#include <cstddef>
#include <cstdio>
#include <cstring>

#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/device.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/layout_id.hpp"
#include "afhub/shm_layout/packed_body_state.hpp"
#include "afhub/shm_layout/payload_check.hpp"
#include "afhub/shm_layout/scene.hpp"
#include "afhub/shm_layout/scene_poses.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub::mcap {

namespace {
constexpr RecordedPayload kPayloads[] = {
    {PayloadKind::kBodyState, "afhub.BodyState", "body_state.hpp", sizeof(BodyState)},
    {PayloadKind::kBodyCommand, "afhub.BodyCommand", "body_command.hpp", sizeof(BodyCommand)},
    {PayloadKind::kWorldState, "afhub.WorldState", "world.hpp", sizeof(WorldState)},
    {PayloadKind::kDeviceState, "afhub.DeviceState", "device.hpp", sizeof(DeviceState)},
    {PayloadKind::kDeviceCommand, "afhub.DeviceCommand", "device.hpp", sizeof(DeviceCommand)},
    {PayloadKind::kSceneDescription, "afhub.SceneDescription", "scene.hpp",
     sizeof(SceneDescription)},
    {PayloadKind::kScenePoses, "afhub.ScenePoses", "scene_poses.hpp", sizeof(ScenePoses)},
};
}  // namespace

std::span<const RecordedPayload> recorded_payloads() {
  return kPayloads;
}

const RecordedPayload& payload_of(PayloadKind kind) {
  for (const RecordedPayload& payload : kPayloads)
    if (payload.kind == kind) return payload;
  throw Error("afhub does not record payloads of kind " +
              std::to_string(static_cast<unsigned>(kind)));
}

namespace {

// A state's counts, when `data` holds them within their capacities.
bool state_counts(std::span<const std::uint8_t> data, std::uint32_t& rays, std::uint32_t& joints) {
  if (data.size() < kPackedReasonAt) return false;
  std::memcpy(&rays, data.data() + offsetof(BodyState, sensor_ray_count), sizeof rays);
  std::memcpy(&joints, data.data() + offsetof(BodyState, joint_count), sizeof joints);
  return rays <= kMaxSensorRaysPerBody && joints <= kMaxJointsPerBody;
}

}  // namespace

std::size_t pieces_for_file(std::span<const std::uint8_t> payload, PayloadKind kind,
                            FilePieces& pieces) {
  std::uint32_t rays = 0, joints = 0;
  if (kind != PayloadKind::kBodyState || !state_counts(payload, rays, joints) ||
      payload.size() != body_state_bytes(joints)) {
    pieces[0] = payload;  // packed already, or not a state: kept as it is (checked on reading)
    return 1;
  }
  pieces = packed_pieces(*reinterpret_cast<const BodyState*>(payload.data()));
  return pieces.size();
}

std::span<const std::uint8_t> checked_copy(std::span<const std::uint8_t> data, PayloadKind kind,
                                           std::vector<std::uint64_t>& buffer,
                                           const std::string& what) {
  std::uint32_t rays = 0, joints = 0;
  const bool packed = kind == PayloadKind::kBodyState && state_counts(data, rays, joints) &&
                      data.size() != body_state_bytes(joints);
  const char* field = nullptr;
  PayloadError error = PayloadError::kNone;
  std::size_t bytes = data.size();
  if (packed) {
    error = check_packed_body_state(data.data(), data.size(), &field);
    bytes = body_state_bytes(joints);
  }
  buffer.assign(bytes / sizeof(std::uint64_t) + 1, 0);
  auto* out = reinterpret_cast<std::uint8_t*>(buffer.data());
  if (!packed) {
    std::memcpy(out, data.data(), data.size());
    error = check_payload(out, bytes, kind, &field);
  } else if (error == PayloadError::kNone) {
    unpack_body_state(data, *reinterpret_cast<BodyState*>(out));
  }
  if (error != PayloadError::kNone)
    throw Error(what + " is not a valid payload (" + field + "): " + describe(error));
  return {out, bytes};
}

std::string joint_names_text(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ",") + name;
  return text;
}

std::vector<std::string> joint_names_in(const Metadata& channel_metadata) {
  std::vector<std::string> names;
  const auto found = channel_metadata.find("joint_names");
  if (found == channel_metadata.end() || found->second.empty()) return names;
  const std::string& text = found->second;
  for (std::size_t from = 0; from <= text.size();) {
    const std::size_t comma = std::min(text.find(',', from), text.size());
    names.push_back(text.substr(from, comma - from));
    from = comma + 1;
  }
  return names;
}

std::string layout_id_text() {
  char text[32];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(kLayoutId));
  return text;
}

void require_this_layout(const std::string& file, const Metadata& metadata) {
  const auto layout = metadata.find("layout_id");
  if (layout == metadata.end() || layout->second != layout_id_text())
    throw Error(file + " was recorded by an afhub of another payload layout (" +
                (layout == metadata.end() ? "none" : layout->second) + "; this one is " +
                layout_id_text() + "): play it with the afhub that recorded it");
}

std::vector<std::uint8_t> payload_schema_text(const RecordedPayload& payload) {
  char text[1024];
  const int n = std::snprintf(
      text, sizeof text,
      "%s: the bytes of the C++ struct afhub::%s (shm_layout/include/afhub/shm_layout/%s) as "
      "they were in shared memory, x86-64 little-endian, cut to the size its writer published "
      "(array entries past a count are left out); at most %zu bytes.%s layout_id 0x%016llx: a "
      "build of another layout id reads them only through this description.\n",
      payload.schema_name, payload.schema_name + 6, payload.header, payload.max_bytes,
      payload.kind != PayloadKind::kBodyState
          ? ""
          : " Packed when its size is below body_state_bytes(joint_count): its bytes before "
            "refusal_reason; refusal_reason and the padding after it, up to "
            "sensor_distances_m, unless the reason was empty (the size says which); the "
            "first sensor_ray_count entries of sensor_distances_m, then of sensor_ranges_m; "
            "its joints. What is left out reads as zeros.",
      static_cast<unsigned long long>(kLayoutId));
  return {text, text + n};
}

}  // namespace afhub::mcap
