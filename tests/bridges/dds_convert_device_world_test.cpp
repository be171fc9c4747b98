// afhub's DDS types carry DeviceState, DeviceCommand, WorldState and WorldCommand at
// full fidelity: each is filled byte by byte (so every field holds a value no default
// has), goes through to_dds, Cyclone's serializer (a writer and a reader of one
// participant) and from_dds into a zeroed payload, and must come out identical,
// except the header fields that the hub's writer stamps on publish (checked on the
// sample instead). A field left uncopied stays zero and fails the comparison.
#include <dds/dds.h>
#include <gtest/gtest.h>

#include <cstring>
#include <memory>

#include "dds_convert_device_world.hpp"
#include "through_cyclone.hpp"

namespace afhub::bridges {
namespace {

// Every byte of `value` different from zero and from its neighbours.
template <typename T>
void fill(T& value) {
  auto* bytes = reinterpret_cast<unsigned char*>(&value);
  for (std::size_t i = 0; i < sizeof(T); ++i) bytes[i] = static_cast<unsigned char>(1 + i % 250);
}

// Every byte zero, padding included, as a payload loaned from a fresh chunk could be.
template <typename T>
void zero(T& value) {
  std::memset(static_cast<void*>(&value), 0, sizeof(T));
}

template <std::size_t N>
void set_text(std::array<char, N>& field, const char* text) {
  field.fill('\0');
  std::strncpy(field.data(), text, N - 1);
}

// What from_dds sets of a header (the hub's writer stamps the rest).
PayloadHeader carried(const PayloadHeader& header) {
  PayloadHeader out;
  out.sim_step = header.sim_step;
  out.sim_time_s = header.sim_time_s;
  return out;
}

template <typename Sample>
void expect_header_on_sample(const PayloadHeader& header, const Sample& sample) {
  EXPECT_EQ(sample.header.sequence_number, header.sequence);
  EXPECT_EQ(sample.header.sim_step, header.sim_step);
  EXPECT_EQ(sample.header.sim_time_s, header.sim_time_s);
  EXPECT_EQ(sample.header.source_stamp_ns, header.publish_stamp_ns);
  EXPECT_EQ(sample.header.publisher_pid, header.publisher_pid);
}

template <typename T>
void expect_same_bytes(const T& expected, const T& got) {
  const auto* a = reinterpret_cast<const unsigned char*>(&expected);
  const auto* b = reinterpret_cast<const unsigned char*>(&got);
  for (std::size_t i = 0; i < sizeof(T); ++i)
    ASSERT_EQ(a[i], b[i]) << "first difference at byte " << i << " of " << sizeof(T);
}

TEST(DdsConvertDeviceWorld, DeviceStateRoundTripsEveryField) {
  auto from = std::make_unique<DeviceState>();
  fill(*from);
  set_text(from->spec.model, "Novint Falcon");
  set_text(from->spec.serial, "FA12345");
  from->gate = ForceGate::kWatchdog;
  std::memset(from->reserved, 0, sizeof from->reserved);  // not carried
  from->spec.reserved = 0;
  afhub_dds_DeviceState sample{}, received{};
  to_dds("device/falcon", *from, sample);
  EXPECT_STREQ(sample.device, "device/falcon");
  expect_header_on_sample(from->header, sample);
  ASSERT_NO_FATAL_FAILURE(through_cyclone(&afhub_dds_DeviceState_desc, sample, received));
  auto to = std::make_unique<DeviceState>();
  zero(*to);
  ASSERT_TRUE(from_dds(received, *to));
  DeviceState expected = *from;
  expected.header = carried(from->header);
  expect_same_bytes(expected, *to);
  // A gate that no driver writes is refused.
  received.gate = 5;
  EXPECT_FALSE(from_dds(received, *to));
}

TEST(DdsConvertDeviceWorld, DeviceCommandRoundTripsEveryField) {
  DeviceCommand from;
  fill(from);
  std::memset(from.reserved, 0, sizeof from.reserved);
  afhub_dds_DeviceCommand sample{}, received{};
  to_dds("device/falcon", from, sample);
  EXPECT_STREQ(sample.device, "device/falcon");
  expect_header_on_sample(from.header, sample);
  ASSERT_NO_FATAL_FAILURE(through_cyclone(&afhub_dds_DeviceCommand_desc, sample, received));
  DeviceCommand to;
  zero(to);
  from_dds(received, to);
  DeviceCommand expected = from;
  expected.header = carried(from.header);
  expect_same_bytes(expected, to);
}

TEST(DdsConvertDeviceWorld, WorldStateRoundTripsEveryField) {
  auto from = std::make_unique<WorldState>();
  fill(*from);
  from->reserved = 0;
  set_text(from->last_nan_body, "afhub/arm/link3");
  from->light_count = 3;
  from->camera_count = kMaxWorldObjects;  // full
  for (std::size_t i = 0; i < kMaxWorldObjects; ++i) {
    set_text(from->lights[i].name, ("light" + std::to_string(i)).c_str());
    set_text(from->cameras[i].name, ("camera" + std::to_string(i)).c_str());
    if (i >= from->light_count) zero(from->lights[i]);  // beyond the count: not carried
  }
  afhub_dds_WorldState sample, received;
  make_world_state_sample(sample);
  make_world_state_sample(received);
  to_dds("world", *from, sample);
  EXPECT_STREQ(sample.world, "world");
  expect_header_on_sample(from->header, sample);
  ASSERT_NO_FATAL_FAILURE(through_cyclone(&afhub_dds_WorldState_desc, sample, received));
  // Taken into the sample's own buffers, not reallocated ones.
  EXPECT_EQ(received.lights._maximum, kMaxWorldObjects);
  auto to = std::make_unique<WorldState>();
  zero(*to);
  from_dds(received, *to);
  auto expected = std::make_unique<WorldState>(*from);
  expected->header = carried(from->header);
  // The physics' phase is on the other machine's clock: not carried.
  expected->step_due_ns = 0;
  expected->step_period_ns = 0;
  expect_same_bytes(*expected, *to);
  free_world_state_sample(sample);
  free_world_state_sample(received);
}

TEST(DdsConvertDeviceWorld, WorldCommandRoundTripsAndUnknownActionsAreRefused) {
  WorldCommand from;
  fill(from);
  from.action = WorldAction::kPause;
  from.hold_ms = 1000;  // a held pause keeps its hold on the other machine
  from.valid_ms = 5000;
  afhub_dds_WorldCommand sample{}, received{};
  to_dds("world", from, sample);
  expect_header_on_sample(from.header, sample);
  ASSERT_NO_FATAL_FAILURE(through_cyclone(&afhub_dds_WorldCommand_desc, sample, received));
  WorldCommand to;
  zero(to);
  ASSERT_TRUE(from_dds(received, to));
  WorldCommand expected = from;
  expected.header = carried(from.header);
  expect_same_bytes(expected, to);
  received.action = 6;
  EXPECT_FALSE(from_dds(received, to));
  received.action = 1;
  received.hold_ms = kMaxPauseHoldMs + 1;
  EXPECT_FALSE(from_dds(received, to));
  received.hold_ms = 0;
  received.valid_ms = kMaxWorldCommandValidMs + 1;
  EXPECT_FALSE(from_dds(received, to));
}

}  // namespace
}  // namespace afhub::bridges
