// Health: what the hub publishes once a second about the whole system.
#pragma once

#include <array>
#include <cstdint>

#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {

struct ProcessEntry {
  std::array<char, kProcessNameBufferSize> name{};
  std::int32_t pid{0};
  std::uint32_t reserved{0};
};

struct MempoolUsage {
  std::uint32_t segment_id{0};  // iceoryx segment: RouDi's own introspection pools, then payloads
  std::uint32_t chunk_payload_bytes{0};
  std::uint32_t chunk_count{0};
  std::uint32_t used_chunks{0};
  std::uint32_t min_free_chunks{0};  // low-water mark since the hub started
};

struct Health {
  static constexpr PayloadKind kKind = PayloadKind::kHealth;
  PayloadHeader header;
  double hub_uptime_s{0.0};
  std::uint32_t process_count{0};
  std::uint32_t mempool_count{0};
  std::uint32_t body_count{0};
  // iceoryx publisher ports left in the whole system (one per body state, per
  // command writer, per loop's stats): a process checks before it asks for more.
  std::uint32_t free_publisher_ports{0};
  // iceoryx subscriber ports left (one per reader: a command slot, a state read by
  // a controller, a bridge or the hub's rate probe): checked the same way.
  std::uint32_t free_subscriber_ports{0};
  std::array<ProcessEntry, kMaxHealthProcesses> processes{};
  std::array<MempoolUsage, kMaxMempools> mempools{};
};

}  // namespace afhub
