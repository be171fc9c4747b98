// The ring protocol (see tape_ring.hpp).
#include "tape_ring.hpp"

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <memory>

#include "afhub/shm_layout/layout_id.hpp"
#include "latest_slot.hpp"

namespace afhub::tape_ring {

namespace {
constexpr std::uint64_t whole(std::uint64_t k) {
  return 2 * k + 2;
}
}  // namespace

void init(StepTapeRing& ring, std::int64_t made_ns, std::uint32_t writer_pid) noexcept {
  ring.id = {kStepTapeRingMagic, kLayoutId, made_ns, writer_pid, kStepTapeRingParts};
  std::construct_at(&ring.written, 0U);
  for (StepTapeRingPart& part : ring.parts) std::construct_at(&part.sequence, 0U);
}

StepTape& open(StepTapeRing& ring, std::uint64_t k) noexcept {
  StepTapeRingPart& part = ring.parts[k % kStepTapeRingParts];
  part.sequence.store(whole(k) - 1, std::memory_order_relaxed);
  // The odd sequence is visible before any write to the part.
  std::atomic_thread_fence(std::memory_order_release);
  return part.tape;
}

void close(StepTapeRing& ring, std::uint64_t k) noexcept {
  ring.parts[k % kStepTapeRingParts].sequence.store(whole(k), std::memory_order_release);
  ring.written.store(k + 1, std::memory_order_release);
}

Read read(const StepTapeRing& ring, std::uint64_t k, StepTape& out, std::uint32_t& bytes) noexcept {
  const StepTapeRingPart& part = ring.parts[k % kStepTapeRingParts];
  const std::uint64_t before = part.sequence.load(std::memory_order_acquire);
  if (before < whole(k)) return Read::kNotYet;
  if (before > whole(k)) return Read::kOverwritten;
  constexpr std::size_t kHead = offsetof(StepTape, data);
  slot::copy_racing(&out, &part.tape, kHead);
  const std::uint32_t data_bytes = std::min<std::uint32_t>(out.data_bytes, out.data.size());
  slot::copy_racing(out.data.data(), part.tape.data.data(), data_bytes);
  // The copy's reads complete before the sequence is read again.
  std::atomic_thread_fence(std::memory_order_acquire);
  if (part.sequence.load(std::memory_order_relaxed) != before) return Read::kOverwritten;
  bytes = static_cast<std::uint32_t>(kHead + data_bytes);
  return Read::kCopied;
}

std::uint64_t resume_after_lap(const StepTapeRing& ring, std::uint64_t k) noexcept {
  const std::uint64_t written = ring.written.load(std::memory_order_acquire);
  constexpr std::uint64_t kBehind = kStepTapeRingParts - kStepTapeRingParts / 4;
  return std::max(k + 1, written > kBehind ? written - kBehind : 0);
}

std::uint64_t head(const StepTapeRing& ring) noexcept {
  return ring.written.load(std::memory_order_acquire);
}

}  // namespace afhub::tape_ring
