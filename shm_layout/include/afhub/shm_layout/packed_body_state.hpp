// A body state packed: without what its counts leave empty. The refusal reason is kept
// whole once a command was refused and left out before; each sensor array keeps its
// first sensor_ray_count entries; the joints follow. With 8 joints, no ray and no
// refusal: 508 of the state's 1184 bytes. The form of a state on the step tape and in a
// recording, where every step's every state is copied and compressed.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/payload_check.hpp"

namespace afhub {

inline constexpr std::size_t kPackedReasonAt = offsetof(BodyState, refusal_reason);
// The reason's bytes up to the sensor arrays (its padding with it).
inline constexpr std::size_t kPackedReasonBytes =
    offsetof(BodyState, sensor_distances_m) - kPackedReasonAt;

constexpr std::size_t packed_body_state_bytes(bool reason, std::uint32_t rays,
                                              std::uint32_t joints) {
  return kPackedReasonAt + (reason ? kPackedReasonBytes : 0) + 2 * rays * sizeof(double) +
         joints * sizeof(JointSample);
}

// The pieces of a whole state (`bytes` of it, valid: the writer's own or checked), in
// packed order: concatenated, they are the packed state.
using PackedPieces = std::array<std::span<const std::uint8_t>, 4>;
PackedPieces packed_pieces(const BodyState& state) noexcept;

// A packed state of `bytes` checked as check_payload checks a whole one: its header, its
// counts, its size (which of the two its counts allow), its reason terminated.
PayloadError check_packed_body_state(const void* data, std::size_t bytes,
                                     const char** field = nullptr) noexcept;

// A checked packed state unpacked into `out`: a reason left out reads as empty, the
// sensor arrays past the count are not written. Returns the whole state's bytes.
std::size_t unpack_body_state(std::span<const std::uint8_t> packed, BodyState& out) noexcept;

}  // namespace afhub
