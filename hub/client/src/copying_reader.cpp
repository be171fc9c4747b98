// A reader that copies before it checks (see copying_reader.hpp).
#include "afhub/hub/copying_reader.hpp"

#include <cstdio>
#include <cstring>

#include "afhub/shm_layout/payload_check.hpp"
#include "afhub/shm_layout/slot.hpp"

namespace afhub {

CopyingReader::CopyingReader(const ChannelId& channel, PayloadKind kind)
    : reader_(channel, kind), kind_(kind) {}

const void* CopyingReader::latest() {
  if (is_slot_kind(kind_)) {
    const void* copy = reader_.latest();
    updated_ = reader_.updated();
    return copy;
  }
  updated_ = false;
  // The in-place check of RawLatestReader sorts out honest mistakes (another build's
  // layout); the check of the copy below is the one that counts.
  const void* shared = reader_.latest();
  if (reader_.updated()) {
    const std::uint32_t bytes = reader_.latest_bytes();
    // Into the spare buffer, which becomes the copy once checked (no allocation once
    // both buffers have grown to the channel's payload size).
    spare_.resize((bytes + sizeof(std::max_align_t) - 1) / sizeof(std::max_align_t));
    std::memcpy(spare_.data(), shared, bytes);
    const char* field = "";
    const PayloadError error = check_payload(spare_.data(), bytes, kind_, &field);
    if (error == PayloadError::kNone) {
      copy_.swap(spare_);
      have_copy_ = true;
      updated_ = true;
    } else if (refused_++ == 0) {
      const ChannelId& id = reader_.channel();
      std::fprintf(stderr,
                   "afhub: refused a payload on %s/%s/%s: it changed while it was read (%s: "
                   "%s); its writer is faulty or hostile (said once per reader)\n",
                   id.service.c_str(), id.instance.c_str(), id.event.c_str(), field,
                   describe(error));
    }
  }
  return have_copy_ ? copy_.data() : nullptr;
}

}  // namespace afhub
