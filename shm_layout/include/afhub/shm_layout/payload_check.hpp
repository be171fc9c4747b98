// Checks a received chunk before anything reads it: size, layout id, kind and
// every count it holds. A payload comes from another process and is untrusted:
// once it passes, every count is within its array and within the chunk.
// Real-time safe: no allocation, no exceptions.
#pragma once

#include <cstddef>
#include <cstdint>

#include "afhub/shm_layout/geometry.hpp"
#include "afhub/shm_layout/header.hpp"

namespace afhub {

enum class PayloadError : std::uint8_t {
  kNone = 0,
  kTooSmall,       // chunk shorter than the payload it claims to be
  kForeignLayout,  // written by a build with another kLayoutId
  kWrongKind,      // another payload type on this channel
  // A field out of its range: a count beyond the payload's capacity or the chunk's
  // bytes, an unknown enum value, a pose or force that is not finite.
  kCountTooLarge,
};

// Checks `bytes` bytes at `data` as a payload of `expected` kind. When `field` is
// given, it is set to the field at fault ("BodyCommand.actuator_count"), or to ""
// when the payload is valid.
PayloadError check_payload(const void* data, std::size_t bytes, PayloadKind expected,
                           const char** field = nullptr) noexcept;

// The field of a device's reading that check_payload refuses in a DeviceState (a number
// that is not finite: "DeviceState.pose"), or nullptr: its driver checks a sample with it
// before publishing.
const char* device_reading_problem(const Pose& pose, const Twist& velocity,
                                   double gripper_angle_rad) noexcept;

// One line for the user: what is wrong with the payload and what to do about it.
const char* describe(PayloadError error) noexcept;

}  // namespace afhub
