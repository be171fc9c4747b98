// The viewer's own WebSocket pieces: the handshake key (RFC 6455's example) and frame
// headers, short and long, in both directions.
#include "websocket_frames.hpp"

#include <gtest/gtest.h>

namespace afhub::viewer {
namespace {

TEST(WebSocketFrames, TheAcceptKeyIsTheRfcsExample) {
  EXPECT_EQ(websocket_accept("dGhlIHNhbXBsZSBub25jZQ=="), "s3pPLMBiTxaQ9kYGzzhZRbK+xOo=");
}

TEST(WebSocketFrames, AHeaderIsReadOnlyOnceWhole) {
  // A masked close frame with 2 bytes of payload.
  const std::uint8_t close[] = {0x88, 0x82, 1, 2, 3, 4};
  EXPECT_FALSE(parse_frame_header(close, 1));
  EXPECT_FALSE(parse_frame_header(close, 5));
  const auto header = parse_frame_header(close, 6);
  ASSERT_TRUE(header);
  EXPECT_TRUE(header->fin);
  EXPECT_EQ(header->opcode, 0x8);
  EXPECT_TRUE(header->masked);
  EXPECT_EQ(header->length, 2U);
  EXPECT_EQ(header->size, 6U);
  EXPECT_EQ(header->mask[3], 4);
}

TEST(WebSocketFrames, AOneGigabyteFrameSaysSoInItsHeader) {
  const std::uint8_t huge[] = {0x82, 0xFF, 0, 0, 0, 0, 0x40, 0, 0, 0, 9, 9, 9, 9};
  EXPECT_FALSE(parse_frame_header(huge, 13));
  const auto header = parse_frame_header(huge, sizeof huge);
  ASSERT_TRUE(header);
  EXPECT_EQ(header->length, 1ULL << 30);
  EXPECT_EQ(header->size, 14U);
}

TEST(WebSocketFrames, WrittenHeadersReadBack) {
  for (const std::uint64_t length : {0ULL, 125ULL, 126ULL, 65535ULL, 65536ULL, 1ULL << 33}) {
    std::uint8_t out[10];
    const std::size_t size = write_frame_header(out, Opcode::kBinary, length);
    const auto header = parse_frame_header(out, size);
    ASSERT_TRUE(header) << length;
    EXPECT_EQ(header->size, size) << length;
    EXPECT_EQ(header->length, length);
    EXPECT_EQ(header->opcode, 0x2);
    EXPECT_TRUE(header->fin);
    EXPECT_FALSE(header->masked);
  }
}

}  // namespace
}  // namespace afhub::viewer
