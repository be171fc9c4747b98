// The slot protocol (see latest_slot.hpp).
#include "latest_slot.hpp"

#include <linux/futex.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstring>

namespace afhub::slot {
namespace {

// Tries of a read that finds the slot mid-update. A writer's update is a few hundred
// nanoseconds; a reader that finds it busy this often gives up for now (kTorn).
constexpr int kReadTries = 64;

void pause_briefly() noexcept {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

std::uint32_t* futex_word(SlotControl* slot) noexcept {
  static_assert(sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t));
  return reinterpret_cast<std::uint32_t*>(&slot->sequence);
}

timespec monotonic_after(std::int64_t ns) noexcept {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  const std::int64_t at = now.tv_sec * 1'000'000'000LL + now.tv_nsec + ns;
  return {static_cast<time_t>(at / 1'000'000'000LL), static_cast<long>(at % 1'000'000'000LL)};
}

bool any_changed(std::span<const Watch> watches) noexcept {
  for (const Watch& watch : watches)
    if (watch.slot->sequence.load(std::memory_order_seq_cst) != watch.observed) return true;
  return false;
}

}  // namespace

// ThreadSanitizer is told not to look at the copy (it would report every read); its
// plain word loop keeps the compiler from calling the intercepted memcpy.
#if defined(__SANITIZE_THREAD__)
__attribute__((no_sanitize("thread"))) void copy_racing(void* out, const void* in,
                                                        std::size_t bytes) noexcept {
  auto* to = static_cast<volatile unsigned char*>(out);
  const auto* from = static_cast<const volatile unsigned char*>(in);
  for (std::size_t i = 0; i < bytes; ++i) to[i] = from[i];
}
#else
void copy_racing(void* out, const void* in, std::size_t bytes) noexcept {
  std::memcpy(out, in, bytes);
}
#endif

void init(SlotControl& slot) noexcept {
  slot.sequence.store(0, std::memory_order_relaxed);
  slot.sleeping.store(0, std::memory_order_relaxed);
  slot.stamp_ns.store(0, std::memory_order_relaxed);
  slot.payload_bytes.store(0, std::memory_order_relaxed);
}

void begin_update(SlotControl& slot, std::uint32_t bytes) noexcept {
  const std::uint32_t sequence = slot.sequence.load(std::memory_order_relaxed);
  if (!(sequence & 1U)) {
    slot.sequence.store(sequence + 1, std::memory_order_relaxed);
    // The odd sequence is visible before any write to the payload.
    std::atomic_thread_fence(std::memory_order_release);
  }
  slot.payload_bytes.store(bytes, std::memory_order_relaxed);
}

void end_update(SlotControl& slot, std::int64_t stamp_ns) noexcept {
  slot.stamp_ns.store(stamp_ns, std::memory_order_relaxed);
  // A full barrier (seq_cst): the payload before the even sequence, and the sequence
  // before the look at `sleeping`, which a reader sets before it checks the sequence
  // and sleeps. One of the two sees the other, so no wake-up is lost.
  slot.sequence.fetch_add(1, std::memory_order_seq_cst);
  if (slot.sleeping.load(std::memory_order_seq_cst) != 0 &&
      slot.sleeping.exchange(0, std::memory_order_seq_cst) != 0)
    syscall(SYS_futex, futex_word(&slot), FUTEX_WAKE, INT_MAX, nullptr, nullptr, 0);
}

Read read(const SlotControl& slot, const void* payload, std::uint32_t capacity, void* out,
          std::uint32_t& observed, std::uint32_t& copied) noexcept {
  for (int attempt = 0; attempt < kReadTries; ++attempt) {
    const std::uint32_t before = slot.sequence.load(std::memory_order_acquire);
    if (before == observed) return (before & 1U) ? Read::kTorn : Read::kUnchanged;
    if (before & 1U) {
      pause_briefly();
      continue;
    }
    const std::uint32_t bytes =
        std::min(slot.payload_bytes.load(std::memory_order_relaxed), capacity);
    copy_racing(out, payload, bytes);
    // The copy's reads complete before the sequence is read again.
    std::atomic_thread_fence(std::memory_order_acquire);
    if (slot.sequence.load(std::memory_order_relaxed) == before) {
      observed = before;
      copied = bytes;
      return Read::kCopied;
    }
  }
  // Remembered odd, so that a wait sleeps until the writer ends the update (or a
  // restarted writer publishes a new slot), instead of returning at once.
  const std::uint32_t now = slot.sequence.load(std::memory_order_acquire);
  if (now & 1U) observed = now;
  return Read::kTorn;
}

void wait(std::span<const Watch> watches, std::int64_t timeout_ns) noexcept {
  if (watches.empty() || timeout_ns <= 0) return;
  for (const Watch& watch : watches) watch.slot->sleeping.store(1, std::memory_order_seq_cst);
  if (any_changed(watches)) return;
  if (watches.size() == 1) {
    const timespec timeout{static_cast<time_t>(timeout_ns / 1'000'000'000LL),
                           static_cast<long>(timeout_ns % 1'000'000'000LL)};
    // Returns at once (EAGAIN) when the sequence is no longer `observed`.
    syscall(SYS_futex, futex_word(watches[0].slot), FUTEX_WAIT, watches[0].observed, &timeout,
            nullptr, 0);
    return;
  }
  futex_waitv waiters[FUTEX_WAITV_MAX];
  const std::size_t count = std::min<std::size_t>(watches.size(), FUTEX_WAITV_MAX);
  for (std::size_t i = 0; i < count; ++i)
    waiters[i] = {watches[i].observed, reinterpret_cast<std::uint64_t>(futex_word(watches[i].slot)),
                  FUTEX_32, 0};
  timespec deadline = monotonic_after(timeout_ns);
  if (syscall(SYS_futex_waitv, waiters, count, 0, &deadline, CLOCK_MONOTONIC) >= 0 ||
      errno != ENOSYS)
    return;
  // A kernel before 5.16 has no futex_waitv: look every 50 us until the deadline.
  for (;;) {
    if (any_changed(watches)) return;
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    if (now.tv_sec > deadline.tv_sec ||
        (now.tv_sec == deadline.tv_sec && now.tv_nsec >= deadline.tv_nsec))
      return;
    const timespec step{0, 50'000};
    nanosleep(&step, nullptr);
  }
}

}  // namespace afhub::slot
