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

// The first count beyond its capacity, named; nullptr when every count fits.
// The chunk holds at least the kind's fixed size (body lists: their counted bodies).
const char* count_beyond_capacity(const char* at, PayloadKind kind) noexcept {
  switch (kind) {
    case PayloadKind::kBodyState: {
      const auto* state = reinterpret_cast<const BodyState*>(at);
      if (state->joint_count > kMaxJointsPerBody) return "BodyState.joint_count";
      if (state->sensor_ray_count > kMaxSensorRaysPerBody) return "BodyState.sensor_ray_count";
      return nullptr;
    }
    case PayloadKind::kBodyCommand: {
      const auto* command = reinterpret_cast<const BodyCommand*>(at);
      if (command->joint_count > kMaxJointsPerBody) return "BodyCommand.joint_count";
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
    case PayloadKind::kCatalog: {
      const auto* list = reinterpret_cast<const BodyList*>(at);
      for (std::uint32_t i = 0; i < list->body_count; ++i)
        if (list->bodies[i].joint_count > kMaxJointsPerBody) return "BodyInfo.joint_count";
      return nullptr;
    }
    case PayloadKind::kHealth: {
      const auto* health = reinterpret_cast<const Health*>(at);
      if (health->process_count > kMaxHealthProcesses) return "Health.process_count";
      if (health->mempool_count > kMaxMempools) return "Health.mempool_count";
      return nullptr;
    }
    case PayloadKind::kWorldCommand:
    case PayloadKind::kLoopStats:
    case PayloadKind::kBenchSample:
      return nullptr;
  }
  return nullptr;
}

PayloadError fail(PayloadError error, const char* what, const char** field) noexcept {
  if (field) *field = what;
  return error;
}

}  // namespace

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
  if (expected == PayloadKind::kBodyDirectory || expected == PayloadKind::kCatalog) {
    const std::uint32_t count = reinterpret_cast<const BodyList*>(at)->body_count;
    if (count > kMaxBodies || bytes < body_list_bytes(count))
      return fail(PayloadError::kCountTooLarge, "BodyList.body_count", field);
  }
  if (const char* count = count_beyond_capacity(at, expected))
    return fail(PayloadError::kCountTooLarge, count, field);
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
