// Checking a block of slots before reading its entries (see slot_block.hpp).
#include "afhub/shm_layout/layout_id.hpp"
#include "afhub/shm_layout/slot_block.hpp"

namespace afhub {

SlotBlockError check_slot_block(const SlotBlockHeader& header, std::size_t chunk_bytes,
                                PayloadKind expected, SlotBlockGeometry& geometry,
                                const char** field) noexcept {
  *field = "";
  if (chunk_bytes < kSlotBlockHeaderBytes) return *field = "chunk", SlotBlockError::kTooSmall;
  const auto* volatile_header = static_cast<const volatile SlotBlockHeader*>(&header);
  const std::uint64_t magic = volatile_header->magic;
  const std::uint64_t layout_id = volatile_header->layout_id;
  const PayloadKind kind = volatile_header->kind;
  const std::uint32_t pid = volatile_header->writer_pid;
  const std::uint32_t count = volatile_header->entry_count;
  const std::uint32_t bytes = volatile_header->entry_bytes;
  if (magic != kSlotBlockMagic) return *field = "SlotBlockHeader.magic", SlotBlockError::kNotABlock;
  if (layout_id != kLayoutId)
    return *field = "SlotBlockHeader.layout_id", SlotBlockError::kForeignLayout;
  if (kind != expected) return *field = "SlotBlockHeader.kind", SlotBlockError::kWrongKind;
  if (count == 0 || count > kMaxSlotBlockEntries)
    return *field = "SlotBlockHeader.entry_count", SlotBlockError::kBadGeometry;
  if (bytes <= kSlotEntryHeaderBytes || bytes % 64 != 0)
    return *field = "SlotBlockHeader.entry_bytes", SlotBlockError::kBadGeometry;
  if (kSlotBlockHeaderBytes + static_cast<std::uint64_t>(count) * bytes > chunk_bytes)
    return *field = "SlotBlockHeader.entry_count", SlotBlockError::kTooSmall;
  geometry = {pid, count, bytes, bytes - kSlotEntryHeaderBytes};
  return SlotBlockError::kNone;
}

const char* describe(SlotBlockError error) noexcept {
  switch (error) {
    case SlotBlockError::kNone:
      return "valid";
    case SlotBlockError::kTooSmall:
      return "the chunk is shorter than the block of slots it claims to be";
    case SlotBlockError::kNotABlock:
      return "not a block of slots (a writer of another afhub version?): rebuild both sides "
             "from the same sources";
    case SlotBlockError::kForeignLayout:
      return "written by a build with another shared-memory layout: rebuild both sides from "
             "the same sources";
    case SlotBlockError::kWrongKind:
      return "a block of another payload kind on this channel";
    case SlotBlockError::kBadGeometry:
      return "an entry count or entry size out of range";
  }
  return "unknown";
}

}  // namespace afhub
