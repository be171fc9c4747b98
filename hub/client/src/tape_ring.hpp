// The protocol of a step tape's ring (StepTapeRing, see shm_layout/step_tape.hpp) over
// plain memory: no iceoryx here, so it is tested on its own, under ThreadSanitizer
// too. Every function is allocation-free and noexcept.
#pragma once

#include <cstdint>

#include "afhub/shm_layout/step_tape.hpp"

namespace afhub::tape_ring {

// A fresh ring: its id, and every part unwritten (its data left as it is).
void init(StepTapeRing& ring, std::int64_t made_ns, std::uint32_t writer_pid) noexcept;

// Writer: opens the ring's `k`-th part (its sequence odd, so that a reader copying the
// part it replaces finds its copy overwritten) and returns it to fill; close() makes it
// whole. Parts are opened in order and closed in order; a writer may open a few ahead
// (StepTapeWriter::prepare) before it closes the first.
StepTape& open(StepTapeRing& ring, std::uint64_t k) noexcept;
void close(StepTapeRing& ring, std::uint64_t k) noexcept;

enum class Read {
  kCopied,       // `out` holds the k-th part, `bytes` of it (not checked yet)
  kNotYet,       // not whole yet (being written, or its writer gone)
  kOverwritten,  // the writer lapped the reader: the part is gone
};

// Copies the ring's `k`-th part into `out`, its header and its used data.
Read read(const StepTapeRing& ring, std::uint64_t k, StepTape& out, std::uint32_t& bytes) noexcept;

// Where a reader lapped at part `k` starts again: a quarter of the ring past the oldest
// part kept (three quarters behind the writer), so that it is not lapped again at once;
// past `k` whatever the ring says.
std::uint64_t resume_after_lap(const StepTapeRing& ring, std::uint64_t k) noexcept;

// The part the writer will close next.
std::uint64_t head(const StepTapeRing& ring) noexcept;

}  // namespace afhub::tape_ring
