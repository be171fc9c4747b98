// FalconDevice against a scripted transport: grip buttons and position from replies,
// forces through the kinematics, homing, and a device that stops answering.
#include <gtest/gtest.h>

#include <cmath>
#include <deque>

#include "afhub/devices/falcon_device.hpp"

namespace afhub::devices::falcon {
namespace {

// Answers each packet with the next scripted reply (none left: no reply) and keeps
// what was sent.
struct ScriptedTransport : FalconTransport {
  std::deque<TransportReply>* replies;
  std::vector<Command>* sent;
  TransportReply exchange(const Packet& command) override {
    sent->push_back(decode_command(command).command);
    if (replies->empty()) return {};
    const TransportReply reply = replies->front();
    replies->pop_front();
    return reply;
  }
};

TransportReply at(const Vec& position_k, std::uint8_t buttons = 0, std::uint8_t homed = 7) {
  const auto angles = inverse(position_k);
  Reply reply{{}, buttons, homed};
  for (int leg = 0; leg < 3; ++leg) {
    reply.encoders[leg] = static_cast<std::int16_t>(std::lround(angle_to_encoder((*angles)[leg])));
  }
  return {encode_reply(reply), true};
}

class FalconDeviceTest : public ::testing::Test {
 protected:
  FalconDevice make(DeviceOptions options = {}) {
    auto transport = std::make_unique<ScriptedTransport>();
    transport->replies = &replies_;
    transport->sent = &sent_;
    return FalconDevice(std::move(transport), "S1", options);
  }
  std::deque<TransportReply> replies_;
  std::vector<Command> sent_;
};

TEST_F(FalconDeviceTest, SpecIsTheFalcons) {
  const DeviceSpec spec = make().spec();
  EXPECT_STREQ(spec.model.data(), "Novint Falcon");
  EXPECT_STREQ(spec.serial.data(), "S1");
  EXPECT_EQ(spec.max_force_n, 8.0);
  EXPECT_EQ(spec.max_stiffness_npm, 3000.0);
  EXPECT_EQ(spec.workspace_radius_m, 0.04);
  EXPECT_EQ(spec.sensed, kDeviceTranslation);
  EXPECT_EQ(spec.actuated, kDeviceTranslation);
  EXPECT_EQ(spec.button_count, 4U);
}

TEST_F(FalconDeviceTest, PositionAndButtonsInTheDeviceFrame) {
  FalconDevice device = make();
  // Kinematic (x right, y up, z to the user) 1 cm right, 2 cm up, 3 cm out.
  replies_.push_back(at({0.01, 0.02, 0.11 + 0.03}, 0b1010));
  const DeviceSample sample = device.exchange(DeviceOutput{});
  // Device frame: x to the user, y right, z up; within an encoder count (~0.1 mm).
  EXPECT_NEAR(sample.pose.position_m.x, 0.03, 2e-4);
  EXPECT_NEAR(sample.pose.position_m.y, 0.01, 2e-4);
  EXPECT_NEAR(sample.pose.position_m.z, 0.02, 2e-4);
  EXPECT_EQ(sample.buttons, 0b1010U);
}

TEST_F(FalconDeviceTest, AForceUpDrivesTheMotorsThroughTheJacobian) {
  FalconDevice device = make();
  replies_.push_back(at(kWorkspaceCentre));
  replies_.push_back(at(kWorkspaceCentre));
  device.exchange(DeviceOutput{});
  DeviceOutput up;
  up.wrench.force_n.z = 4.0;  // device z is kinematic y
  device.exchange(up);
  const auto expected = force_to_torques(kWorkspaceCentre, {0.0, 4.0, 0.0});
  ASSERT_TRUE(expected);
  ASSERT_EQ(sent_.size(), 2U);
  EXPECT_EQ(sent_[0].motors, (std::array<std::int16_t, 3>{0, 0, 0}));
  for (int leg = 0; leg < 3; ++leg) {
    EXPECT_NEAR(device.last_torques()[leg], expected->torque_nm[leg], 1e-4);
  }
  EXPECT_NE(sent_[1].motors, (std::array<std::int16_t, 3>{0, 0, 0}));
  device.make_safe();
  EXPECT_EQ(sent_.back().motors, (std::array<std::int16_t, 3>{0, 0, 0}));
}

// Destroyed without a make_safe (an exception unwinding past its owner), the Falcon still
// gets a last packet at zero force.
TEST_F(FalconDeviceTest, DestroyedItSendsAPacketAtZeroForce) {
  const std::array<std::int16_t, 3> zero{0, 0, 0};
  {
    FalconDevice device = make();
    replies_.push_back(at(kWorkspaceCentre));
    replies_.push_back(at(kWorkspaceCentre));
    device.exchange(DeviceOutput{});
    DeviceOutput up;
    up.wrench.force_n.z = 4.0;
    device.exchange(up);
    ASSERT_NE(sent_.back().motors, zero);
  }
  EXPECT_EQ(sent_.back().motors, zero);
}

TEST_F(FalconDeviceTest, HomingWaitsForAllThreeLegs) {
  FalconDevice device = make();
  replies_.push_back(at(kWorkspaceCentre, 0, 0b001));
  replies_.push_back(at(kWorkspaceCentre, 0, 0b011));
  replies_.push_back(at(kWorkspaceCentre, 0, 0b111));
  EXPECT_TRUE(device.home(10));
  EXPECT_TRUE(sent_.front().homing);
  EXPECT_EQ(sent_.front().leds, kLedRed);
  EXPECT_FALSE(sent_.back().homing);
  EXPECT_EQ(sent_.back().leds, kLedGreen);
  replies_.push_back(at(kWorkspaceCentre, 0, 0b011));
  EXPECT_FALSE(make().home(1));
}

TEST_F(FalconDeviceTest, MalformedOrMissingRepliesEndInDeviceGone) {
  DeviceOptions options;
  options.max_bad_replies = 3;
  FalconDevice device = make(options);
  replies_.push_back(at(kWorkspaceCentre, 0b0001));
  const DeviceSample good = device.exchange(DeviceOutput{});
  TransportReply garbled = at(kWorkspaceCentre);
  garbled.packet[4] = 0x20;
  replies_.push_back(garbled);
  replies_.push_back(garbled);
  // A bad reply keeps the last sample.
  EXPECT_EQ(device.exchange(DeviceOutput{}).buttons, good.buttons);
  device.exchange(DeviceOutput{});
  replies_.push_back(garbled);
  try {
    device.exchange(DeviceOutput{});
    FAIL() << "three malformed replies in a row were accepted";
  } catch (const DeviceGone& gone) {
    EXPECT_NE(std::string(gone.what()).find("byte 4 is 0x20"), std::string::npos) << gone.what();
  }
  FalconDevice silent = make(options);  // no replies scripted: the Falcon is silent
  silent.exchange(DeviceOutput{});
  silent.exchange(DeviceOutput{});
  EXPECT_THROW(silent.exchange(DeviceOutput{}), DeviceGone);
}

}  // namespace
}  // namespace afhub::devices::falcon
