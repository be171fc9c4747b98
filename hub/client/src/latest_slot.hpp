// The seqlock and futex protocol of a latest-value slot (SlotControl, see
// shm_layout/slot.hpp), over plain memory: no iceoryx here, so the protocol is
// tested on its own, under ThreadSanitizer too. Every function is allocation-free
// and noexcept.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "afhub/shm_layout/slot.hpp"

namespace afhub::slot {

// Copies memory a writer may be writing at the same time: the sequence read after it
// says whether the copy counts.
void copy_racing(void* out, const void* in, std::size_t bytes) noexcept;

// A fresh slot, before its chunk is published.
void init(SlotControl& slot) noexcept;

// Writer: begin_update makes the sequence odd (the payload may then be written in
// place, `bytes` of it); end_update records the payload's stamp, makes the sequence
// even and wakes any reader asleep on it. begin_update on a slot already odd (an
// update begun and never ended) keeps it odd.
void begin_update(SlotControl& slot, std::uint32_t bytes) noexcept;
void end_update(SlotControl& slot, std::int64_t stamp_ns) noexcept;

enum class Read {
  kCopied,     // `out` holds an update newer than `observed`
  kUnchanged,  // the sequence is still `observed`
  kTorn,       // mid-update (its writer busy, or killed in it): try again later
};

// Copies the update's bytes of `payload` (at most `capacity`, the chunk's) into `out`
// when the slot holds an update other than `observed` (the sequence this reader last
// saw), and sets `observed` to the sequence it found and `copied` to the bytes. Gives
// up after a few tries on a slot being written, rather than wait for a writer that may
// be gone: `out` then holds garbage, and the caller keeps its copy.
Read read(const SlotControl& slot, const void* payload, std::uint32_t capacity, void* out,
          std::uint32_t& observed, std::uint32_t& copied) noexcept;

// One slot a reader waits on, and the sequence it last saw there.
struct Watch {
  SlotControl* slot;
  std::uint32_t observed;
};

// Sleeps until one of the first 128 of `watches` (futex_waitv's most) changes, or
// `timeout_ns` passes.
void wait(std::span<const Watch> watches, std::int64_t timeout_ns) noexcept;

}  // namespace afhub::slot
