// A block of slots comes from another process: its header is checked before any entry
// is read, and every check names the field at fault.
#include "afhub/shm_layout/slot_block.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <new>

#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/layout_id.hpp"

namespace afhub {
namespace {

struct Forged {
  static constexpr std::uint32_t kEntries = 4, kCapacity = 1024;
  Forged()
      : bytes(slot_block_bytes(kEntries, kCapacity)),
        memory(new (std::align_val_t{64}) unsigned char[bytes]) {
    header = new (memory.get()) SlotBlockHeader;
    header->magic = kSlotBlockMagic;
    header->layout_id = kLayoutId;
    header->kind = PayloadKind::kBodyState;
    header->writer_pid = 42;
    header->entry_count = kEntries;
    header->entry_bytes = kSlotEntryHeaderBytes + kCapacity;
  }
  SlotBlockError check(const char** field, std::size_t chunk = 0) {
    return check_slot_block(*header, chunk ? chunk : bytes, PayloadKind::kBodyState, geometry,
                            field);
  }
  std::size_t bytes;
  struct Free {
    void operator()(unsigned char* p) const { ::operator delete[](p, std::align_val_t{64}); }
  };
  std::unique_ptr<unsigned char[], Free> memory;
  SlotBlockHeader* header;
  SlotBlockGeometry geometry;
};

TEST(SlotBlock, AWellFormedBlockPassesWithItsGeometry) {
  Forged block;
  const char* field = "unset";
  ASSERT_EQ(block.check(&field), SlotBlockError::kNone);
  EXPECT_STREQ(field, "");
  EXPECT_EQ(block.geometry.writer_pid, 42u);
  EXPECT_EQ(block.geometry.entry_count, Forged::kEntries);
  EXPECT_EQ(block.geometry.payload_capacity, Forged::kCapacity);
}

TEST(SlotBlock, EachBadFieldIsNamed) {
  const char* field = "";
  {
    Forged block;
    block.header->magic = 0;
    EXPECT_EQ(block.check(&field), SlotBlockError::kNotABlock);
    EXPECT_STREQ(field, "SlotBlockHeader.magic");
  }
  {
    Forged block;
    block.header->layout_id ^= 1;
    EXPECT_EQ(block.check(&field), SlotBlockError::kForeignLayout);
    EXPECT_STREQ(field, "SlotBlockHeader.layout_id");
  }
  {
    Forged block;
    block.header->kind = PayloadKind::kBodyCommand;
    EXPECT_EQ(block.check(&field), SlotBlockError::kWrongKind);
    EXPECT_STREQ(field, "SlotBlockHeader.kind");
  }
  for (std::uint32_t count : {0u, kMaxSlotBlockEntries + 1, 0xffffffffu}) {
    Forged block;
    block.header->entry_count = count;
    EXPECT_NE(block.check(&field), SlotBlockError::kNone) << count;
    EXPECT_STREQ(field, "SlotBlockHeader.entry_count") << count;
  }
  for (std::uint32_t bytes :
       {0u, kSlotEntryHeaderBytes, kSlotEntryHeaderBytes + 100, 0xffffffc0u}) {
    Forged block;
    block.header->entry_bytes = bytes;
    const SlotBlockError error = block.check(&field);
    EXPECT_NE(error, SlotBlockError::kNone) << bytes;
    EXPECT_NE(std::strstr(field, "SlotBlockHeader.entry_"), nullptr) << bytes << ": " << field;
  }
  {
    Forged block;  // entries past the chunk's end
    EXPECT_EQ(block.check(&field, block.bytes - 1), SlotBlockError::kTooSmall);
    EXPECT_STREQ(field, "SlotBlockHeader.entry_count");
    EXPECT_EQ(block.check(&field, kSlotBlockHeaderBytes - 1), SlotBlockError::kTooSmall);
    EXPECT_STREQ(field, "chunk");
  }
  EXPECT_NE(std::strstr(describe(SlotBlockError::kForeignLayout), "rebuild"), nullptr);
}

// Writers and the hub size blocks by the same rules; every block is within its tier,
// or holds a single entry.
TEST(SlotBlock, BlocksFillTheirTierOrHoldOneEntry) {
  for (std::uint32_t bytes : {1u, 200u, 1160u, 2528u, 8192u, 8193u, 25568u, 1u << 20}) {
    const std::uint32_t capacity = slot_payload_capacity(bytes);
    EXPECT_GE(capacity, bytes);
    EXPECT_EQ(capacity % 64, 0u);
    for (std::size_t nth = 0; nth < 6; ++nth) {
      const std::uint32_t entries = slot_block_entries(nth, capacity);
      const std::size_t loaned = slot_block_loan_bytes(nth, capacity);
      ASSERT_GE(entries, 1u);
      EXPECT_LE(slot_block_bytes(entries, capacity), loaned) << bytes;
      if (slot_block_tier(nth, capacity) == 0) {  // larger than every tier: one entry
        EXPECT_EQ(entries, 1u);
        continue;
      }
      EXPECT_GE(loaned, kSlotBlockTiers[std::min(nth, kSlotBlockTierCount - 1)]) << bytes;
      EXPECT_GT(slot_block_bytes(entries + 1, capacity), loaned) << bytes << ": room left";
    }
  }
  // A thousand states of 7 joints (1160 bytes) take five blocks.
  std::uint32_t held = 0, blocks = 0;
  while (held < 1000) held += slot_block_entries(blocks++, slot_payload_capacity(1160));
  EXPECT_EQ(blocks, 5u);
}

}  // namespace
}  // namespace afhub
