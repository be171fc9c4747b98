// A block of latest-value slots: one iceoryx chunk that a writer process publishes
// once and that holds the slots of many channels of one kind (a physics's thousand
// body states, a controller's commands to every body it drives). iceoryx 2.0.3 as
// Debian builds it has 512 publisher and 1024 subscriber ports for the whole system;
// a port per body would cap a world near 450 bodies. With blocks, a process takes a
// publisher per block, and a reader process one subscriber per kind.
//
// Layout: a SlotBlockHeader, then `entry_count` entries of `entry_bytes` each: a
// SlotEntryHeader (the slot's control block, see slot.hpp, and its channel's name),
// then the payload, `entry_bytes - kSlotEntryHeaderBytes` bytes at most. The writer
// fills an entry's name, then raises `claimed` past it; a name never changes after.
// An entry whose writer let it go (closed, or moved to a larger entry) keeps its last
// update and is never written again; the block is `closed` when all of its entries
// are, and readers let go of it a moment later.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>

#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "afhub/shm_layout/slot.hpp"

namespace afhub {

// The iceoryx service every block of one kind is published on: service, the kind's
// number as the instance, event.
inline constexpr char kSlotBlockService[] = "afhub-slots";
inline constexpr char kSlotBlockEvent[] = "blocks";

inline constexpr std::uint64_t kSlotBlockMagic = 0x61666875622d626cULL;  // "afhub-bl"

struct alignas(64) SlotBlockHeader {
  std::uint64_t magic{0};      // kSlotBlockMagic
  std::uint64_t layout_id{0};  // kLayoutId of the writer's build
  PayloadKind kind{};          // of every entry
  std::uint32_t writer_pid{0};
  std::uint32_t entry_count{0};  // entries the block has room for
  std::uint32_t entry_bytes{0};  // from one entry to the next (a multiple of 64)
  // Entries [0, claimed) carry their channel's name. Raised (release) after a name is
  // written: a reader that reads it (acquire) may read the names below it.
  std::atomic<std::uint32_t> claimed{0};
  // 1 once the writer claims no more entries in it and has let go of every one.
  std::atomic<std::uint32_t> closed{0};
};

struct alignas(64) SlotEntryHeader {
  SlotControl control;
  // Readers holding the entry now: a writer with none may skip the work of an update
  // nobody reads (a viewer's pose feed). A reader killed holding it leaves it counted.
  std::atomic<std::uint32_t> readers{0};
  // The channel's service, instance and event, each null-terminated.
  char service[kChannelNameBufferSize]{};
  char instance[kChannelNameBufferSize]{};
  char event[kChannelNameBufferSize]{};
};

inline constexpr std::uint32_t kSlotBlockHeaderBytes = sizeof(SlotBlockHeader);
inline constexpr std::uint32_t kSlotEntryHeaderBytes = sizeof(SlotEntryHeader);
static_assert(kSlotBlockHeaderBytes == 64 && kSlotEntryHeaderBytes % 64 == 0);

// Entries of a block are at most this many: a reader scans a block's new entries
// when it looks for channels, and a writer fills one block before it loans the next.
inline constexpr std::uint32_t kMaxSlotBlockEntries = 4096;

// The bytes of a block of `entries` entries, each with room for `payload_capacity`.
constexpr std::size_t slot_block_bytes(std::uint32_t entries, std::uint32_t payload_capacity) {
  return kSlotBlockHeaderBytes + static_cast<std::size_t>(entries) *
                                     (kSlotEntryHeaderBytes + (payload_capacity + 63) / 64 * 64);
}

// How writers size blocks; the hub sizes its pools by the same rules.
//
// An entry's room for a payload of `bytes`: a power of two up to 8 KiB (at least
// 256 B), so that states of bodies with similar joint counts share a block; above, a
// multiple of 4 KiB.
constexpr std::uint32_t slot_payload_capacity(std::uint32_t bytes) {
  if (bytes > (8u << 10)) return (bytes + 4095) / 4096 * 4096;
  std::uint32_t capacity = 256;
  while (capacity < bytes) capacity *= 2;
  return capacity;
}

// The chunk sizes of blocks: a writer's n-th block for one kind and entry size is a
// chunk of tier n (the last tier thereafter), or of the first tier that holds one
// entry, filled with as many entries as fit. A process writing a few channels takes
// one 16 KiB block; a physics of a thousand body states five blocks. A payload larger
// than the last tier gets a block of one entry, of its own size. The hub's pools have
// these sizes, so a block always takes a chunk of its tier.
inline constexpr std::uint32_t kSlotBlockTiers[] = {16u << 10, 64u << 10, 256u << 10, 1u << 20};
inline constexpr std::size_t kSlotBlockTierCount = 4;

// The tier of a writer's `nth_block`, or 0 when no tier holds one entry.
constexpr std::uint32_t slot_block_tier(std::size_t nth_block, std::uint32_t payload_capacity) {
  for (std::size_t tier = nth_block < kSlotBlockTierCount ? nth_block : kSlotBlockTierCount - 1;
       tier < kSlotBlockTierCount; ++tier)
    if (slot_block_bytes(1, payload_capacity) <= kSlotBlockTiers[tier])
      return kSlotBlockTiers[tier];
  return 0;
}

constexpr std::uint32_t slot_block_entries(std::size_t nth_block, std::uint32_t payload_capacity) {
  const std::uint32_t tier = slot_block_tier(nth_block, payload_capacity);
  if (tier == 0) return 1;
  const std::uint32_t stride = kSlotEntryHeaderBytes + (payload_capacity + 63) / 64 * 64;
  const std::uint32_t entries = (tier - kSlotBlockHeaderBytes) / stride;
  return entries > kMaxSlotBlockEntries ? kMaxSlotBlockEntries : entries;
}

// The chunk a writer loans for its `nth_block`.
constexpr std::size_t slot_block_loan_bytes(std::size_t nth_block, std::uint32_t payload_capacity) {
  const std::uint32_t tier = slot_block_tier(nth_block, payload_capacity);
  return tier != 0 ? tier : slot_block_bytes(1, payload_capacity);
}

// The payload size of a pool whose chunks hold a block of `loan_bytes`: iceoryx pads a
// chunk for the block's 64-byte alignment.
constexpr std::size_t slot_block_pool_bytes(std::size_t loan_bytes) {
  return loan_bytes + 64;
}

// The chunk of a writer's first block for payloads of `bytes`.
constexpr std::size_t first_slot_block_bytes(std::uint32_t bytes) {
  return slot_block_loan_bytes(0, slot_payload_capacity(bytes));
}

// The blocks (each a publisher port) a writer process takes for `entries` slots of
// payloads of `bytes`; slots of other sizes take blocks of their own.
constexpr std::size_t slot_blocks_for(std::size_t entries, std::uint32_t bytes) {
  const std::uint32_t capacity = slot_payload_capacity(bytes);
  std::size_t blocks = 0;
  while (entries > 0) {
    const std::size_t held = slot_block_entries(blocks++, capacity);
    entries -= entries < held ? entries : held;
  }
  return blocks;
}

enum class SlotBlockError : std::uint8_t {
  kNone = 0,
  kTooSmall,       // the chunk is shorter than its header or its entries
  kNotABlock,      // no kSlotBlockMagic
  kForeignLayout,  // another build's kLayoutId
  kWrongKind,      // entries of another kind
  kBadGeometry,    // an entry count or size out of range
};

// What a reader may rely on once a block's header passed check_slot_block.
struct SlotBlockGeometry {
  std::uint32_t writer_pid = 0;
  std::uint32_t entry_count = 0;
  std::uint32_t entry_bytes = 0;
  std::uint32_t payload_capacity = 0;  // entry_bytes - kSlotEntryHeaderBytes
};

// Reads each field of a block's header once (another process writes it), then checks
// the copies against the chunk's `chunk_bytes` and the kind its reader expects; `field`
// is set to the field at fault ("SlotBlockHeader.entry_bytes"). Entries below
// min(claimed, entry_count) are then within the chunk.
SlotBlockError check_slot_block(const SlotBlockHeader& header, std::size_t chunk_bytes,
                                PayloadKind expected, SlotBlockGeometry& geometry,
                                const char** field) noexcept;

const char* describe(SlotBlockError error) noexcept;

}  // namespace afhub
