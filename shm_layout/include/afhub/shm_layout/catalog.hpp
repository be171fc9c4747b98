// The catalog: names travel here once, never in the per-step payloads.
// A process that owns bodies publishes a BodyDirectory of them; the hub merges
// every live directory into the Catalog. Both share one shape and are published
// with only their first body_count entries, so a small directory uses a small chunk.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

struct BodyInfo {
  std::array<char, kChannelNameBufferSize> channel{};  // "<namespace>/<body>", NUL-terminated
  std::array<char, kProcessNameBufferSize> owner{};    // iceoryx runtime name of the publisher
  std::uint32_t owner_pid{0};
  std::uint32_t joint_count{0};
  double publish_rate_hz{0.0};  // measured by the hub; 0 in a directory
  std::array<std::array<char, kJointNameBufferSize>, kMaxJointsPerBody> joint_names{};
};

struct BodyList {
  // No kKind: a BodyList is a kBodyDirectory or a kCatalog, named by its channel.
  PayloadHeader header;
  std::uint32_t body_count{0};
  std::uint32_t reserved{0};
  std::array<BodyInfo, kMaxBodies> bodies{};
};

// Bytes of a BodyList holding `count` bodies: what is loaned and published.
constexpr std::size_t body_list_bytes(std::size_t count) {
  return offsetof(BodyList, bodies) + count * sizeof(BodyInfo);
}

}  // namespace afhub
