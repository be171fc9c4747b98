// The protocol of a tape's ring (TapeRing, see shm_layout/tape_ring.hpp) over plain
// memory: no iceoryx here, so it is tested on its own, under ThreadSanitizer too. Every
// function is allocation-free and noexcept.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <type_traits>

#include "afhub/shm_layout/layout_id.hpp"
#include "afhub/shm_layout/step_tape.hpp"
#include "latest_slot.hpp"

namespace afhub::tape_ring {

namespace detail {
// The sequence of the k-th part once whole.
constexpr std::uint64_t whole(std::uint64_t k) {
  return 2 * k + 2;
}
}  // namespace detail

// A fresh ring: its id, and every part unwritten (its data left as it is).
template <class Ring>
void init(Ring& ring, std::int64_t made_ns, std::uint32_t writer_pid) noexcept {
  ring.id = {Ring::kRingMagic, kLayoutId, made_ns, writer_pid, Ring::kPartCount};
  std::construct_at(&ring.written, 0U);
  for (auto& part : ring.parts) std::construct_at(&part.sequence, 0U);
}

// Writer: opens the ring's `k`-th part (its sequence odd, so that a reader copying the
// part it replaces finds its copy overwritten) and returns it to fill; close() makes it
// whole. Parts are opened in order and closed in order; a writer may open a few ahead
// (StepTapeWriter::prepare) before it closes the first.
template <class Ring>
typename Ring::PartType& open(Ring& ring, std::uint64_t k) noexcept {
  auto& part = ring.parts[k % Ring::kPartCount];
  part.sequence.store(detail::whole(k) - 1, std::memory_order_relaxed);
  // The odd sequence is visible before any write to the part.
  std::atomic_thread_fence(std::memory_order_release);
  return part.tape;
}

template <class Ring>
void close(Ring& ring, std::uint64_t k) noexcept {
  ring.parts[k % Ring::kPartCount].sequence.store(detail::whole(k), std::memory_order_release);
  ring.written.store(k + 1, std::memory_order_release);
}

enum class Read {
  kCopied,       // `out` holds the k-th part, `bytes` of it (not checked yet)
  kNotYet,       // not whole yet (being written, or its writer gone)
  kOverwritten,  // the writer lapped the reader: the part is gone
};

// Copies the ring's `k`-th part into `out`: a step tape's header and its used data, any
// other part whole.
template <class Ring>
Read read(const Ring& ring, std::uint64_t k, typename Ring::PartType& out,
          std::uint32_t& bytes) noexcept {
  const auto& part = ring.parts[k % Ring::kPartCount];
  const std::uint64_t before = part.sequence.load(std::memory_order_acquire);
  if (before < detail::whole(k)) return Read::kNotYet;
  if (before > detail::whole(k)) return Read::kOverwritten;
  std::size_t copied = sizeof out;
  if constexpr (std::is_same_v<typename Ring::PartType, StepTape>) {
    constexpr std::size_t kHead = offsetof(StepTape, data);
    slot::copy_racing(&out, &part.tape, kHead);
    const std::uint32_t data_bytes = std::min<std::uint32_t>(out.data_bytes, out.data.size());
    slot::copy_racing(out.data.data(), part.tape.data.data(), data_bytes);
    copied = kHead + data_bytes;
  } else {
    slot::copy_racing(&out, &part.tape, sizeof out);
  }
  // The copy's reads complete before the sequence is read again.
  std::atomic_thread_fence(std::memory_order_acquire);
  if (part.sequence.load(std::memory_order_relaxed) != before) return Read::kOverwritten;
  bytes = static_cast<std::uint32_t>(copied);
  return Read::kCopied;
}

// Where a reader lapped at part `k` starts again: a quarter of the ring past the oldest
// part kept (three quarters behind the writer), so that it is not lapped again at once;
// past `k` whatever the ring says.
template <class Ring>
std::uint64_t resume_after_lap(const Ring& ring, std::uint64_t k) noexcept {
  const std::uint64_t written = ring.written.load(std::memory_order_acquire);
  constexpr std::uint64_t kBehind = Ring::kPartCount - Ring::kPartCount / 4;
  return std::max(k + 1, written > kBehind ? written - kBehind : 0);
}

// The part the writer will close next.
template <class Ring>
std::uint64_t head(const Ring& ring) noexcept {
  return ring.written.load(std::memory_order_acquire);
}

}  // namespace afhub::tape_ring
