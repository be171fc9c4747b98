// Payload validation: what a reader refuses before reading anything.
#include "afhub/shm_layout/payload_check.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "afhub/shm_layout/layout_id.hpp"

namespace afhub {
namespace {

template <class T>
T stamped(PayloadKind kind) {
  T payload{};
  payload.header.layout_id = kLayoutId;
  payload.header.kind = kind;
  return payload;
}

TEST(PayloadCheck, AcceptsAPayloadOfThisBuild) {
  auto state = stamped<BodyState>(PayloadKind::kBodyState);
  state.joint_count = kMaxJointsPerBody;
  EXPECT_EQ(check_payload(&state, sizeof state, PayloadKind::kBodyState), PayloadError::kNone);
}

TEST(PayloadCheck, RefusesAForeignLayout) {
  auto state = stamped<BodyState>(PayloadKind::kBodyState);
  state.header.layout_id = kLayoutId ^ 1;
  EXPECT_EQ(check_payload(&state, sizeof state, PayloadKind::kBodyState),
            PayloadError::kForeignLayout);
}

TEST(PayloadCheck, RefusesAnotherPayloadKind) {
  auto command = stamped<BodyCommand>(PayloadKind::kBodyCommand);
  EXPECT_EQ(check_payload(&command, sizeof command, PayloadKind::kBodyState),
            PayloadError::kWrongKind);
}

TEST(PayloadCheck, RefusesAChunkShorterThanItsPayload) {
  auto state = stamped<BodyState>(PayloadKind::kBodyState);
  EXPECT_EQ(check_payload(&state, sizeof state - 8, PayloadKind::kBodyState),
            PayloadError::kTooSmall);
  EXPECT_EQ(check_payload(&state, sizeof(PayloadHeader) - 1, PayloadKind::kBodyState),
            PayloadError::kTooSmall);
}

TEST(PayloadCheck, RefusesJointCountsBeyondCapacity) {
  auto state = stamped<BodyState>(PayloadKind::kBodyState);
  state.joint_count = kMaxJointsPerBody + 1;
  EXPECT_EQ(check_payload(&state, sizeof state, PayloadKind::kBodyState),
            PayloadError::kCountTooLarge);
  auto command = stamped<BodyCommand>(PayloadKind::kBodyCommand);
  command.joint_count = 1000;
  EXPECT_EQ(check_payload(&command, sizeof command, PayloadKind::kBodyCommand),
            PayloadError::kCountTooLarge);
}

TEST(PayloadCheck, BodyListsMustHoldTheBodiesTheyCount) {
  std::vector<unsigned char> bytes(body_list_bytes(2));
  PayloadHeader header{kLayoutId, PayloadKind::kCatalog};
  std::memcpy(bytes.data(), &header, sizeof header);
  std::uint32_t count = 2;
  std::memcpy(bytes.data() + offsetof(BodyList, body_count), &count, sizeof count);
  EXPECT_EQ(check_payload(bytes.data(), bytes.size(), PayloadKind::kCatalog), PayloadError::kNone);
  count = 3;  // claims one more body than the chunk holds
  std::memcpy(bytes.data() + offsetof(BodyList, body_count), &count, sizeof count);
  EXPECT_EQ(check_payload(bytes.data(), bytes.size(), PayloadKind::kCatalog),
            PayloadError::kCountTooLarge);
}

TEST(PayloadCheck, EveryErrorHasAnExplanation) {
  for (auto error : {PayloadError::kTooSmall, PayloadError::kForeignLayout,
                     PayloadError::kWrongKind, PayloadError::kCountTooLarge})
    EXPECT_GT(std::strlen(describe(error)), 30u);
}

TEST(Layout, PayloadsFitTheirMempoolsAndStaySmall) {
  EXPECT_LE(sizeof(BodyState), 2048u);
  EXPECT_LE(sizeof(BodyCommand), 1024u);
  EXPECT_EQ(sizeof(PayloadHeader), 48u);
}

}  // namespace
}  // namespace afhub
