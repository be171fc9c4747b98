// The pieces that every conversion to and from afhub's DDS types shares (bodies in
// dds_convert.cpp; devices and the world in dds_convert_device_world.cpp): the
// geometry, the header, names, and samples' full-capacity sequences.
#pragma once

#include <dds/dds.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <type_traits>

#include "afhub/shm_layout/geometry.hpp"
#include "afhub/shm_layout/header.hpp"
#include "afhub_dds.h"

namespace afhub::bridges {

inline afhub_dds_Vec3 to_dds(const Vec3& v) noexcept {
  return {v.x, v.y, v.z};
}
inline Vec3 from_dds(const afhub_dds_Vec3& v) noexcept {
  return {v.x, v.y, v.z};
}
inline afhub_dds_Pose to_dds(const Pose& p) noexcept {
  return {to_dds(p.position_m),
          {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w}};
}
inline Pose from_dds(const afhub_dds_Pose& p) noexcept {
  return {from_dds(p.position_m),
          {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w}};
}
inline afhub_dds_Twist to_dds(const Twist& t) noexcept {
  return {to_dds(t.linear_mps), to_dds(t.angular_radps)};
}
inline Twist from_dds(const afhub_dds_Twist& t) noexcept {
  return {from_dds(t.linear_mps), from_dds(t.angular_radps)};
}
inline afhub_dds_Wrench to_dds(const Wrench& w) noexcept {
  return {to_dds(w.force_n), to_dds(w.torque_nm)};
}
inline Wrench from_dds(const afhub_dds_Wrench& w) noexcept {
  return {from_dds(w.force_n), from_dds(w.torque_nm)};
}

inline afhub_dds_Header to_dds(const PayloadHeader& h) noexcept {
  return {h.sequence, h.sim_step, h.sim_time_s, h.publish_stamp_ns, h.publisher_pid};
}
// Only the sim step and time: the hub's writer stamps the rest on publish.
inline void from_dds(const afhub_dds_Header& sample, PayloadHeader& header) noexcept {
  header.sim_step = sample.sim_step;
  header.sim_time_s = sample.sim_time_s;
}

// A NUL-terminated text of `from` (at most N - 1 characters, up to a NUL) into `to`.
template <std::size_t N>
void copy_text(const char* from, std::size_t from_size, char (&to)[N]) noexcept {
  const std::size_t length = strnlen(from, std::min(from_size, N - 1));
  std::memcpy(to, from, length);
  to[length] = '\0';
}
template <std::size_t N>
void copy_text(std::string_view from, char (&to)[N]) noexcept {
  copy_text(from.data(), from.size(), to);
}
template <std::size_t N, std::size_t M>
void copy_text(const char (&from)[M], std::array<char, N>& to) noexcept {
  const std::size_t length = strnlen(from, std::min(M, N - 1));
  std::memcpy(to.data(), from, length);
  to[length] = '\0';
}

// A sequence made to hold `capacity` elements, zeroed, that Cyclone frees with its
// sample (dds_sample_free): written into and taken into with no reallocation.
template <typename Sequence>
void reserve(Sequence& sequence, std::uint32_t capacity) {
  using Element = std::remove_pointer_t<decltype(sequence._buffer)>;
  sequence._buffer = static_cast<Element*>(dds_alloc(sizeof(Element) * capacity));
  std::memset(static_cast<void*>(sequence._buffer), 0, sizeof(Element) * capacity);
  sequence._maximum = capacity;
  sequence._length = 0;
  sequence._release = true;
}

}  // namespace afhub::bridges
