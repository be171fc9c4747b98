// Channel naming: {"afhub", "<namespace>/<body>", "state" | "command"}, the
// world, catalog, health and directory channels, and the lookup of a body by a
// unique suffix of its name.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace afhub {

inline constexpr std::string_view kService = "afhub";
inline constexpr std::string_view kStateEvent = "state";
inline constexpr std::string_view kCommandEvent = "command";
inline constexpr std::string_view kDirectoryEvent = "directory";
inline constexpr std::string_view kWorldInstance = "world";
inline constexpr std::string_view kHubInstance = "hub";
inline constexpr std::string_view kCatalogEvent = "catalog";
inline constexpr std::string_view kHealthEvent = "health";
inline constexpr std::string_view kSceneEvent = "scene";  // {"afhub", <world instance>, "scene"}
// {"afhub", <world instance>, "scene_poses"}: shm_layout/scene_poses.hpp
inline constexpr std::string_view kScenePosesEvent = "scene_poses";
// Tapes: {"afhub", <world instance>, "step_tape"} (shm_layout/step_tape.hpp) and
// {"afhub", <device channel>, "tape"} (shm_layout/device_tape.hpp).
inline constexpr std::string_view kStepTapeEvent = "step_tape";
inline constexpr std::string_view kDeviceTapeEvent = "tape";
// {"afhub", <soft body channel>, "soft_faces" | "soft_nodes"}: shm_layout/soft_body.hpp
inline constexpr std::string_view kSoftFacesEvent = "soft_faces";
inline constexpr std::string_view kSoftNodesEvent = "soft_nodes";
inline constexpr std::string_view kStatsEvent = "stats";  // {"afhub", <runtime name>, "stats"}

// A channel's three iceoryx strings.
struct ChannelId {
  std::string service;
  std::string instance;
  std::string event;
  std::string to_string() const { return service + "/" + instance + "/" + event; }
};

// "<namespace>/<body>" with leading, trailing and doubled slashes removed, and
// spaces removed from the body name as AMBF does ("base link" -> "baselink").
std::string body_channel_name(std::string_view name_space, std::string_view body_name);

// Empty string when `name` can be a channel instance, else what is wrong with it.
std::string channel_name_problem(std::string_view name);

// Throws afhub::Error with a clear message when the name cannot be used.
void require_valid_channel_name(std::string_view name);

// The world's channel instance: "world", or "<namespace>/world" for a physics run
// under a namespace (`afhub run --namespace`), whose world is its own.
std::string world_instance(std::string_view name_space = {});

// A device driver's channel instance: "device/<name>". Throws afhub::Error when
// the name cannot be one.
std::string device_channel_name(std::string_view device_name);

// A body's (or a device's) state and command channels.
ChannelId body_state_channel(std::string_view body_channel);
ChannelId body_command_channel(std::string_view body_channel);

// Finds `query` among `channels`: an exact name, or a unique suffix that starts
// after a '/' ("base" finds "ambf/env/base"). Throws afhub::Error listing the
// candidates when the query is unknown or ambiguous.
std::string resolve_body(std::string_view query, const std::vector<std::string>& channels);

}  // namespace afhub
