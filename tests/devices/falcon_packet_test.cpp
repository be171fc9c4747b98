// The Falcon's 16-byte packets: the recorded vectors of the research notes, round
// trips, and malformed packets refused with the byte that is wrong.
#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "afhub/devices/falcon_packet.hpp"

namespace afhub::devices::falcon {
namespace {

// Recorded host -> device packets (libnifalcon, see the research notes).
constexpr Packet kRecordedBlue{0x3c, 0x50, 0x50, 0x50, 0x41, 0x43, 0x45, 0x50,
                               0x41, 0x43, 0x4d, 0x50, 0x41, 0x45, 0x41, 0x3e};
constexpr Packet kRecordedSecond{0x3c, 0x41, 0x4d, 0x4b, 0x41, 0x4d, 0x4e, 0x4b,
                                 0x41, 0x49, 0x45, 0x4c, 0x41, 0x45, 0x41, 0x3e};

TEST(FalconPacket, RecordedPacketsDecode) {
  const DecodedCommand first = decode_command(kRecordedBlue);
  ASSERT_TRUE(first.ok()) << describe(first.fault);
  EXPECT_EQ(first.command.motors, (std::array<std::int16_t, 3>{4095, 3906, 4034}));
  EXPECT_EQ(first.command.leds, kLedBlue);
  EXPECT_FALSE(first.command.homing);

  const DecodedCommand second = decode_command(kRecordedSecond);
  ASSERT_TRUE(second.ok()) << describe(second.fault);
  EXPECT_EQ(second.command.motors, (std::array<std::int16_t, 3>{2752, 2780, 2888}));
  EXPECT_EQ(second.command.leds, kLedBlue);
}

TEST(FalconPacket, RecordedPacketsEncodeExactly) {
  EXPECT_EQ(hex(encode({{4095, 3906, 4034}, kLedBlue, false})), hex(kRecordedBlue));
  EXPECT_EQ(hex(encode({{2752, 2780, 2888}, kLedBlue, false})), hex(kRecordedSecond));
}

TEST(FalconPacket, HomingAndLedsShareByteThirteen) {
  const Packet packet = encode({{0, 0, 0}, kLedRed | kLedGreen, true});
  EXPECT_EQ(packet[13], 0x41 + (0x8 | 0x2 | 0x1));
  const DecodedCommand decoded = decode_command(packet);
  ASSERT_TRUE(decoded.ok());
  EXPECT_TRUE(decoded.command.homing);
  EXPECT_EQ(decoded.command.leds, kLedRed | kLedGreen);
}

TEST(FalconPacket, CommandsRoundTripOverTheWholeRange) {
  std::mt19937 random(15);
  std::uniform_int_distribution<int> value(std::numeric_limits<std::int16_t>::min(),
                                           std::numeric_limits<std::int16_t>::max());
  std::vector<Command> commands{{{-32768, 32767, 0}, kAllLeds, true}, {{-1, 1, -2}, 0, false}};
  for (int i = 0; i < 1000; ++i) {
    commands.push_back(
        {{static_cast<std::int16_t>(value(random)), static_cast<std::int16_t>(value(random)),
          static_cast<std::int16_t>(value(random))},
         static_cast<std::uint8_t>(value(random) & kAllLeds),
         (i % 2) == 0});
  }
  for (const Command& command : commands) {
    const Packet packet = encode(command);
    for (std::size_t i = 1; i < 15; ++i) {
      EXPECT_GE(packet[i], 0x41);  // printable, as the firmware expects
      EXPECT_LE(packet[i], 0x50);
    }
    const DecodedCommand decoded = decode_command(packet);
    ASSERT_TRUE(decoded.ok()) << hex(packet);
    EXPECT_EQ(decoded.command.motors, command.motors);
    EXPECT_EQ(decoded.command.leds, command.leds);
    EXPECT_EQ(decoded.command.homing, command.homing);
  }
}

TEST(FalconPacket, RepliesRoundTrip) {
  for (std::uint8_t buttons = 0; buttons < 16; ++buttons) {
    for (std::uint8_t homed = 0; homed < 8; ++homed) {
      const Reply reply{
          {static_cast<std::int16_t>(-1000 * buttons), 32767, -32768}, buttons, homed};
      const DecodedReply decoded = decode_reply(encode_reply(reply));
      ASSERT_TRUE(decoded.ok()) << describe(decoded.fault);
      EXPECT_EQ(decoded.reply.encoders, reply.encoders);
      EXPECT_EQ(decoded.reply.grip_buttons, buttons);
      EXPECT_EQ(decoded.reply.homed, homed);
    }
  }
}

TEST(FalconPacket, MalformedRepliesNameTheByte) {
  const Packet good = encode_reply({{100, -200, 300}, 0x5, 0x7});
  struct Case {
    std::size_t byte;
    std::uint8_t value;
    PacketError error;
    const char* says;
  };
  const Case cases[] = {
      {0, 0x3e, PacketError::kBadStart, "byte 0 is 0x3e, not '<'"},
      {15, 0x3c, PacketError::kBadEnd, "byte 15 is 0x3c, not '>'"},
      {1, 0x40, PacketError::kBadNibble, "byte 1 is 0x40, not 0x41 + a nibble"},
      {12, 0x51, PacketError::kBadNibble, "byte 12 is 0x51, not 0x41 + a nibble"},
      {7, 0x00, PacketError::kBadNibble, "byte 7 is 0x00"},
      {13, 0xc1, PacketError::kBadStatus, "byte 13 (buttons and homing) is 0xc1"},
      {13, 0x40, PacketError::kBadStatus, "byte 13 (buttons and homing) is 0x40"},
  };
  for (const Case& c : cases) {
    Packet bad = good;
    bad[c.byte] = c.value;
    const DecodedReply decoded = decode_reply(bad);
    ASSERT_FALSE(decoded.ok()) << hex(bad);
    EXPECT_EQ(decoded.fault.error, c.error);
    EXPECT_EQ(decoded.fault.byte, c.byte);
    EXPECT_NE(describe(decoded.fault).find(c.says), std::string::npos) << describe(decoded.fault);
  }
  // A command's byte 13 carries only a nibble.
  Packet command = encode(Command{});
  command[13] = 0x51;
  EXPECT_EQ(decode_command(command).fault.error, PacketError::kBadStatus);
}

}  // namespace
}  // namespace afhub::devices::falcon
