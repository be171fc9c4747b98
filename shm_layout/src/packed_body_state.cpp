// The packed form of a body state (see packed_body_state.hpp).
#include "afhub/shm_layout/packed_body_state.hpp"

#include <cstring>

namespace afhub {

PackedPieces packed_pieces(const BodyState& state) noexcept {
  const auto* at = reinterpret_cast<const std::uint8_t*>(&state);
  const bool reason = state.refusal_reason[0] != '\0';
  const std::size_t ray_bytes = state.sensor_ray_count * sizeof(double);
  return {std::span(at, kPackedReasonAt + (reason ? kPackedReasonBytes : 0)),
          std::span(at + offsetof(BodyState, sensor_distances_m), ray_bytes),
          std::span(at + offsetof(BodyState, sensor_ranges_m), ray_bytes),
          std::span(at + offsetof(BodyState, joints), state.joint_count * sizeof(JointSample))};
}

std::size_t unpack_body_state(std::span<const std::uint8_t> packed, BodyState& out) noexcept {
  auto* to = reinterpret_cast<std::uint8_t*>(&out);
  const std::uint8_t* from = packed.data();
  const auto take = [&](std::size_t offset, std::size_t n) {
    std::memcpy(to + offset, from, n);
    from += n;
  };
  take(0, kPackedReasonAt);
  if (out.sensor_ray_count > kMaxSensorRaysPerBody || out.joint_count > kMaxJointsPerBody)
    return 0;  // not checked: cannot happen for a caller that checked
  const bool reason =
      packed.size() == packed_body_state_bytes(true, out.sensor_ray_count, out.joint_count);
  if (reason)
    take(kPackedReasonAt, kPackedReasonBytes);
  else
    std::memset(to + kPackedReasonAt, 0, kPackedReasonBytes);
  take(offsetof(BodyState, sensor_distances_m), out.sensor_ray_count * sizeof(double));
  take(offsetof(BodyState, sensor_ranges_m), out.sensor_ray_count * sizeof(double));
  take(offsetof(BodyState, joints), out.joint_count * sizeof(JointSample));
  return body_state_bytes(out.joint_count);
}

}  // namespace afhub
