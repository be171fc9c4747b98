// afhub's DDS types carry BodyState and BodyCommand at full fidelity: every field
// through to_dds and from_dds, serialized and deserialized by Cyclone in between
// (a writer and a reader of one participant: local delivery, with no network), and a
// network command with an out-of-range type is refused.
#include <dds/dds.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>

#include "afhub/bridges/dds_bridge.hpp"
#include "afhub/hub/bodies.hpp"
#include "dds_convert.hpp"
#include "through_cyclone.hpp"

namespace afhub::bridges {
namespace {

BodyState* make_state(std::uint32_t joints) {
  auto* state = static_cast<BodyState*>(std::calloc(1, sizeof(BodyState)));
  state->joint_count = joints;
  return state;
}

TEST(DdsConvert, StateRoundTripsEveryField) {
  std::unique_ptr<BodyState, decltype(&std::free)> from(make_state(7), &std::free);
  from->header = {0, PayloadKind::kBodyState, 1234, 42, 4242, 4.242, 987654321};
  from->pose = {{1, 2, 3}, {0.1, 0.2, 0.3, 0.9}};
  from->twist = {{4, 5, 6}, {7, 8, 9}};
  from->wrench = {{10, 11, 12}, {13, 14, 15}};
  from->contact_wrench = {{16, 17, 18}, {19, 20, 21}};
  from->contact_count = 5;
  from->mass_kg = 2.5;
  from->principal_inertia_kgm2 = {0.1, 0.2, 0.3};
  from->step_due_ns = 987000000;
  from->commanded_steps = 77;
  from->answered_steps = 76;
  from->command_answered_step = 4240;
  from->sensor_ray_count = 3;
  from->sensor_distances_m[0] = 0.5;
  from->sensor_distances_m[2] = -1;
  for (std::uint32_t j = 0; j < 7; ++j) from->joints[j] = {0.1 * j, 0.2 * j, 0.3 * j};

  afhub_dds_BodyState sample, received;
  make_state_sample(sample);
  make_state_sample(received);
  to_dds("afhub/arm/base", *from, sample);
  EXPECT_STREQ(sample.body, "afhub/arm/base");
  EXPECT_EQ(sample.header.sequence_number, 42u);
  EXPECT_EQ(sample.header.source_stamp_ns, 987654321);
  EXPECT_EQ(sample.header.publisher_pid, 1234u);

  ASSERT_NO_FATAL_FAILURE(through_cyclone(&afhub_dds_BodyState_desc, sample, received));
  // Taken into the sample's own full-capacity buffers, not reallocated ones.
  EXPECT_EQ(received.joints._maximum, kMaxJointsPerBody);

  std::unique_ptr<BodyState, decltype(&std::free)> to(make_state(7), &std::free);
  to->step_due_ns = -1;  // a loaned chunk's leftover
  from_dds(received, *to);
  EXPECT_EQ(to->step_due_ns, 0) << "a due time of the other machine's clock is not carried";
  EXPECT_EQ(to->header.sim_step, 4242u);
  EXPECT_EQ(to->header.sim_time_s, 4.242);
  EXPECT_EQ(to->pose.position_m.z, 3);
  EXPECT_EQ(to->pose.orientation.w, 0.9);
  EXPECT_EQ(to->twist.angular_radps.x, 7);
  EXPECT_EQ(to->wrench.torque_nm.z, 15);
  EXPECT_EQ(to->contact_wrench.force_n.x, 16);
  EXPECT_EQ(to->contact_wrench.torque_nm.z, 21);
  EXPECT_EQ(to->contact_count, 5u);
  EXPECT_EQ(to->mass_kg, 2.5);
  EXPECT_EQ(to->principal_inertia_kgm2.y, 0.2);
  EXPECT_EQ(to->commanded_steps, 77u);
  EXPECT_EQ(to->answered_steps, 76u);
  EXPECT_EQ(to->command_answered_step, 4240);
  EXPECT_EQ(to->sensor_ray_count, 3u);
  EXPECT_EQ(to->sensor_distances_m[2], -1);
  ASSERT_EQ(to->joint_count, 7u);
  for (std::uint32_t j = 0; j < 7; ++j) {
    EXPECT_EQ(to->joints[j].position, 0.1 * j);
    EXPECT_EQ(to->joints[j].velocity, 0.2 * j);
    EXPECT_EQ(to->joints[j].effort, 0.3 * j);
  }
  // A loan for fewer joints than the sample carries takes only those.
  std::unique_ptr<BodyState, decltype(&std::free)> smaller(make_state(3), &std::free);
  from_dds(received, *smaller);
  EXPECT_EQ(smaller->joint_count, 3u);
  free_state_sample(sample);
  free_state_sample(received);
}

TEST(DdsConvert, CommandRoundTripsAndBadTypesAreRefused) {
  auto* from = static_cast<BodyCommand*>(std::calloc(1, sizeof(BodyCommand)));
  from->joint_count = 2;
  from->header.sim_step = 9;
  from->cartesian_type = CartesianCommandType::kVelocity;
  from->lockstep = 1;
  from->pose.position_m.x = 1.5;
  from->wrench.force_n.y = -2;
  from->twist.linear_mps.z = 3;
  from->actuator_count = 2;
  from->actuate[1] = 1;
  from->joints[0] = {0.25, JointCommandType::kPosition, {}};
  from->joints[1] = {-1.5, JointCommandType::kEffort, {}};
  afhub_dds_BodyCommand sample;
  make_command_sample(sample);
  to_dds("afhub/arm/base", *from, sample);
  auto* to = static_cast<BodyCommand*>(std::calloc(1, sizeof(BodyCommand)));
  to->joint_count = 2;
  ASSERT_TRUE(from_dds(sample, *to));
  EXPECT_EQ(to->header.sim_step, 9u);
  EXPECT_EQ(to->cartesian_type, CartesianCommandType::kVelocity);
  EXPECT_EQ(to->lockstep, 1);
  EXPECT_EQ(to->pose.position_m.x, 1.5);
  EXPECT_EQ(to->wrench.force_n.y, -2);
  EXPECT_EQ(to->twist.linear_mps.z, 3);
  EXPECT_EQ(to->actuator_count, 2u);
  EXPECT_EQ(to->actuate[1], 1);
  EXPECT_EQ(to->joints[0].type, JointCommandType::kPosition);
  EXPECT_EQ(to->joints[0].value, 0.25);
  EXPECT_EQ(to->joints[1].value, -1.5);

  sample.joints._buffer[1].type = 7;
  EXPECT_FALSE(from_dds(sample, *to));
  sample.joints._buffer[1].type = 0;
  sample.cartesian_type = 3;
  EXPECT_FALSE(from_dds(sample, *to));
  free_command_sample(sample);
  std::free(from);
  std::free(to);
}

TEST(DdsConvert, BodyGlobsMatchChannelNames) {
  EXPECT_TRUE(matches_any("afhub/arm/base", {"afhub/arm/*"}));
  EXPECT_TRUE(matches_any("afhub/arm/base", {"x", "*base"}));
  EXPECT_FALSE(matches_any("afhub/env/box", {"afhub/arm/*"}));
  // The end of a name after a '/', as the command line takes names.
  EXPECT_TRUE(matches_any("afhub/arm/base", {"arm/base"}));
  EXPECT_TRUE(matches_any("afhub/arm/base", {"base"}));
  EXPECT_FALSE(matches_any("afhub/arm/base", {"rm/base"}));
}

}  // namespace
}  // namespace afhub::bridges
