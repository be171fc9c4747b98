#include "recorded_payloads.hpp"

#include <cstdio>
#include <cstring>

#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/device.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/layout_id.hpp"
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

const void* checked_copy(std::span<const std::uint8_t> data, PayloadKind kind,
                         std::vector<std::uint64_t>& buffer, const std::string& what) {
  buffer.resize(data.size() / sizeof(std::uint64_t) + 1);
  std::memcpy(buffer.data(), data.data(), data.size());
  const char* field = nullptr;
  const PayloadError error = check_payload(buffer.data(), data.size(), kind, &field);
  if (error != PayloadError::kNone)
    throw Error(what + " is not a valid payload (" + field + "): " + describe(error));
  return buffer.data();
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
  char text[512];
  const int n = std::snprintf(
      text, sizeof text,
      "%s: the bytes of the C++ struct afhub::%s (shm_layout/include/afhub/shm_layout/%s) as "
      "they were in shared memory, x86-64 little-endian, cut to the size its writer published "
      "(array entries past a count are left out); at most %zu bytes. layout_id 0x%016llx: a "
      "build of another layout id reads them only through this description.\n",
      payload.schema_name, payload.schema_name + 6, payload.header, payload.max_bytes,
      static_cast<unsigned long long>(kLayoutId));
  return {text, text + n};
}

}  // namespace afhub::mcap
