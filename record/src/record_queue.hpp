// The bounded buffer between the recorder's reading loop and its writing thread: one
// producer, one consumer, variable-sized entries in a ring of bytes allocated once.
// push() never blocks and never allocates: when the ring is full it refuses, and the
// caller counts a drop.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>

namespace afhub::mcap {

struct QueuedMessage {
  std::uint32_t bytes = 0;  // of the payload after it
  std::uint16_t channel_id = 0;
  std::uint16_t unused = 0;
  std::uint32_t sequence = 0;
  std::uint32_t unused2 = 0;
  std::uint64_t log_time_ns = 0;
  std::uint64_t publish_time_ns = 0;
};

class RecordQueue {
 public:
  explicit RecordQueue(std::size_t bytes)
      : capacity_(bytes), ring_(std::make_unique<std::uint8_t[]>(bytes)) {}

  // The entry's payload is `pieces` joined.
  bool push(const QueuedMessage& message,
            std::span<const std::span<const std::uint8_t>> pieces) noexcept {
    std::size_t bytes = 0;
    for (const auto& piece : pieces) bytes += piece.size();
    const std::size_t need = entry_bytes(bytes);
    const std::uint64_t head = head_.load(std::memory_order_relaxed);
    const std::uint64_t tail = tail_.load(std::memory_order_acquire);
    std::size_t at = head % capacity_;
    std::size_t skip = 0;  // an entry never wraps: the end of the ring is skipped instead
    if (at + need > capacity_) skip = capacity_ - at;
    if (head + skip + need - tail > capacity_) return false;
    if (skip) {
      if (skip >= sizeof(std::uint32_t)) std::memcpy(ring_.get() + at, &kSkip, sizeof kSkip);
      at = 0;
    }
    QueuedMessage header = message;
    header.bytes = static_cast<std::uint32_t>(bytes);
    std::memcpy(ring_.get() + at, &header, sizeof header);
    at += sizeof header;
    for (const auto& piece : pieces) {
      std::memcpy(ring_.get() + at, piece.data(), piece.size());
      at += piece.size();
    }
    head_.store(head + skip + need, std::memory_order_release);
    return true;
  }

  // Calls `take(const QueuedMessage&, std::span<const std::uint8_t>)` for each entry
  // waiting, oldest first; returns how many.
  template <class Take>
  std::size_t drain(Take&& take) {
    const std::uint64_t head = head_.load(std::memory_order_acquire);
    std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    std::size_t taken = 0;
    while (tail != head) {
      const std::size_t at = tail % capacity_;
      const std::size_t room = capacity_ - at;
      std::uint32_t bytes = kSkip;
      if (room >= sizeof bytes) std::memcpy(&bytes, ring_.get() + at, sizeof bytes);
      if (room < sizeof(QueuedMessage) || bytes == kSkip) {
        tail += room;
        continue;
      }
      QueuedMessage header;
      std::memcpy(&header, ring_.get() + at, sizeof header);
      take(header, std::span<const std::uint8_t>(ring_.get() + at + sizeof header, header.bytes));
      tail += entry_bytes(header.bytes);
      tail_.store(tail, std::memory_order_release);  // room given back entry by entry
      ++taken;
    }
    tail_.store(tail, std::memory_order_release);
    return taken;
  }

  // Bytes waiting: how far the writer is behind.
  std::uint64_t waiting_bytes() const noexcept {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }

 private:
  static constexpr std::uint32_t kSkip = 0xFFFFFFFF;
  static std::size_t entry_bytes(std::size_t payload) {
    return (sizeof(QueuedMessage) + payload + 7) & ~std::size_t{7};
  }

  std::size_t capacity_;
  std::unique_ptr<std::uint8_t[]> ring_;
  alignas(64) std::atomic<std::uint64_t> head_{0};  // bytes ever pushed
  alignas(64) std::atomic<std::uint64_t> tail_{0};  // bytes ever drained
};

}  // namespace afhub::mcap
