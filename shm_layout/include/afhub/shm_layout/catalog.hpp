// The catalog: names travel here once, never in the per-step payloads.
// A process that owns bodies publishes a BodyDirectory of them; the hub merges
// every live directory into the Catalog. Both share one shape and are loaned at
// their real size, body_list_bytes(): the first body_count entries of `bodies`,
// then the names (each distinct name once), then the references into them (per body,
// body_ref_count() of them from first_joint_ref on: its joints, then its sensors' rays,
// its actuators, its children and its parent; see BodyInfo).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

using JointName = std::array<char, kJointNameBufferSize>;  // NUL-terminated

// What a catalog entry's channels carry: a body's BodyState and BodyCommand, or a
// device's DeviceState and DeviceCommand (a driver process, "device/<name>").
enum class ChannelKind : std::uint32_t { kBody = 0, kDevice = 1 };

struct BodyInfo {
  std::array<char, kChannelNameBufferSize> channel{};  // "<namespace>/<body>", NUL-terminated
  std::array<char, kProcessNameBufferSize> owner{};    // iceoryx runtime name of the publisher
  std::uint32_t owner_pid{0};
  std::uint32_t joint_count{0};
  double publish_rate_hz{0.0};  // measured by the hub; 0 in a directory
  // Its joints, in state order, are names[refs[first_joint_ref + i]] for i < joint_count.
  std::uint32_t first_joint_ref{0};
  ChannelKind kind{ChannelKind::kBody};
  // After its joints' refs, in this order: for each sensor ray of its state (in state
  // order, at most kMaxSensorRaysPerBody) the name of the proximity sensor it belongs
  // to; the names of its constraint actuators, in command order (at most
  // kMaxActuatorsPerBody); the names of the bodies jointed directly below it; and its
  // parent's name when it has one (parent_count 1). Body names are the model's, without
  // the namespace, as AMBF's client gives them. So that a client addresses sensors and
  // actuators by name without reading the model's files.
  std::uint32_t sensor_ray_count{0};
  std::uint32_t actuator_count{0};
  std::uint32_t child_count{0};
  std::uint32_t parent_count{0};  // 0 or 1
};

// The references of one body: its joints, sensor rays, actuators, children and parent.
constexpr std::uint64_t body_ref_count(const BodyInfo& body) {
  return std::uint64_t{body.joint_count} + body.sensor_ray_count + body.actuator_count +
         body.child_count + body.parent_count;
}

struct BodyList {
  // No kKind: a BodyList is a kBodyDirectory or a kCatalog, named by its channel.
  PayloadHeader header;
  std::uint32_t body_count{0};
  std::uint32_t joint_name_count{0};
  std::uint32_t joint_ref_count{0};
  std::uint32_t reserved{0};
  // Only the first body_count entries are in the chunk; the names and refs follow them.
  std::array<BodyInfo, kMaxBodies> bodies{};
};

// Bytes of a BodyList holding `count` bodies, `names` joint names and `refs` joint
// references: what is loaned and published.
constexpr std::size_t body_list_bytes(std::size_t count, std::size_t names = 0,
                                      std::size_t refs = 0) {
  return offsetof(BodyList, bodies) + count * sizeof(BodyInfo) + names * sizeof(JointName) +
         refs * sizeof(std::uint32_t);
}

// The sizes body lists are loaned at, each the chunk size of one of the hub's pools
// for them (hub_mempools.cpp). iceoryx takes a chunk from the smallest pool that fits,
// whatever its kind: loaned at their real size, a directory of 8 bodies (2480 bytes)
// took the world state's chunks, and 32 physics ran the world state out of them.
inline constexpr std::array<std::size_t, 3> kBodyListTiers = {
    body_list_bytes(8, 64, 256), body_list_bytes(64, 512, 2048),
    body_list_bytes(kMaxBodies, 8192, 65536)};
// The smallest tier that holds the list (its real size past the last tier).
constexpr std::size_t body_list_loan_bytes(std::size_t count, std::size_t names = 0,
                                           std::size_t refs = 0) {
  const std::size_t bytes = body_list_bytes(count, names, refs);
  for (std::size_t tier : kBodyListTiers)
    if (bytes <= tier) return tier;
  return bytes;
}

// The joint names and references of a list whose counts are set (and, when read,
// checked by check_payload against the chunk's size).
inline JointName* joint_names_in(BodyList& list) {
  return reinterpret_cast<JointName*>(reinterpret_cast<char*>(&list) +
                                      body_list_bytes(list.body_count));
}
inline const JointName* joint_names_in(const BodyList& list) {
  return reinterpret_cast<const JointName*>(reinterpret_cast<const char*>(&list) +
                                            body_list_bytes(list.body_count));
}
inline std::uint32_t* joint_refs_in(BodyList& list) {
  return reinterpret_cast<std::uint32_t*>(reinterpret_cast<char*>(&list) +
                                          body_list_bytes(list.body_count, list.joint_name_count));
}
inline const std::uint32_t* joint_refs_in(const BodyList& list) {
  return reinterpret_cast<const std::uint32_t*>(
      reinterpret_cast<const char*>(&list) +
      body_list_bytes(list.body_count, list.joint_name_count));
}

}  // namespace afhub
