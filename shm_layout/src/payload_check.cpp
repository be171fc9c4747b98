// Validation of received payloads (see payload_check.hpp).
#include "afhub/shm_layout/payload_check.hpp"

#include <cstring>

#include "afhub/shm_layout/layout_id.hpp"
#include "afhub/shm_layout/loop_stats.hpp"

namespace afhub {
namespace {

std::size_t fixed_size_of(PayloadKind kind) noexcept {
  switch (kind) {
    case PayloadKind::kBodyState:
      return sizeof(BodyState);
    case PayloadKind::kBodyCommand:
      return sizeof(BodyCommand);
    case PayloadKind::kWorldState:
      return sizeof(WorldState);
    case PayloadKind::kWorldCommand:
      return sizeof(WorldCommand);
    case PayloadKind::kHealth:
      return sizeof(Health);
    case PayloadKind::kLoopStats:
      return sizeof(LoopStats);
    case PayloadKind::kBenchSample:
      return sizeof(BenchSample);
    case PayloadKind::kBodyDirectory:
    case PayloadKind::kCatalog:
      return body_list_bytes(0);
  }
  return 0;
}

}  // namespace

PayloadError check_payload(const void* data, std::size_t bytes, PayloadKind expected) noexcept {
  if (bytes < sizeof(PayloadHeader)) return PayloadError::kTooSmall;
  PayloadHeader header;
  std::memcpy(&header, data, sizeof header);
  if (header.layout_id != kLayoutId) return PayloadError::kForeignLayout;
  if (header.kind != expected) return PayloadError::kWrongKind;
  if (bytes < fixed_size_of(expected)) return PayloadError::kTooSmall;

  const auto* bytes_at = static_cast<const char*>(data);
  switch (expected) {
    case PayloadKind::kBodyState:
      if (reinterpret_cast<const BodyState*>(bytes_at)->joint_count > kMaxJointsPerBody)
        return PayloadError::kCountTooLarge;
      break;
    case PayloadKind::kBodyCommand:
      if (reinterpret_cast<const BodyCommand*>(bytes_at)->joint_count > kMaxJointsPerBody)
        return PayloadError::kCountTooLarge;
      break;
    case PayloadKind::kBodyDirectory:
    case PayloadKind::kCatalog: {
      const std::uint32_t count = reinterpret_cast<const BodyList*>(bytes_at)->body_count;
      if (count > kMaxBodies || bytes < body_list_bytes(count)) return PayloadError::kCountTooLarge;
      break;
    }
    case PayloadKind::kHealth: {
      const auto* health = reinterpret_cast<const Health*>(bytes_at);
      if (health->process_count > kMaxHealthProcesses || health->mempool_count > kMaxMempools)
        return PayloadError::kCountTooLarge;
      break;
    }
    case PayloadKind::kWorldState:
    case PayloadKind::kWorldCommand:
    case PayloadKind::kLoopStats:
    case PayloadKind::kBenchSample:
      break;
  }
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
      return "a count in the payload exceeds its capacity; the writer is faulty or foreign";
  }
  return "unknown payload error";
}

}  // namespace afhub
