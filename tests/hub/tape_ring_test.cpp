// A tape's ring on its own (hub/client/src/tape_ring.hpp): a reader copying parts
// while the writer writes and laps it never keeps a mixed part and reads them in order
// (a step tape's ring and a device's); a lapped reader starts again behind the writer;
// a part never closed (its writer killed) is not read. Built twice: with the unit tests
// (under ASan and UBSan) and alone under ThreadSanitizer (tape_ring_tsan).
#include "tape_ring.hpp"

#include "afhub/shm_layout/device_tape.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <memory>
#include <thread>

namespace afhub {
namespace {

// Part k: its step k, and its data's words all k.
constexpr std::uint32_t kDataBytes = 16384;

void write_part(StepTapeRing& ring, std::uint64_t k) {
  StepTape& part = tape_ring::open(ring, k);
  part.header.sim_step = k;
  part.data_bytes = kDataBytes;
  for (std::uint32_t at = 0; at < kDataBytes; at += sizeof k)
    std::memcpy(part.data.data() + at, &k, sizeof k);
  tape_ring::close(ring, k);
}

bool all_words_are(const std::uint8_t* data, std::size_t bytes, std::uint64_t k) {
  for (std::size_t at = 0; at + sizeof k <= bytes; at += sizeof k) {
    std::uint64_t word = 0;
    std::memcpy(&word, data + at, sizeof word);
    if (word != k) return false;
  }
  return true;
}

// Whether `part`, `bytes` of it copied, is part k whole.
bool is_part(const StepTape& part, std::uint32_t bytes, std::uint64_t k) {
  return part.header.sim_step == k && bytes == offsetof(StepTape, data) + kDataBytes &&
         all_words_are(part.data.data(), kDataBytes, k);
}

// A device's part k: every word of it k.
void write_part(DeviceTapeRing& ring, std::uint64_t k) {
  DeviceTape& part = tape_ring::open(ring, k);
  for (std::size_t at = 0; at + sizeof k <= sizeof part; at += sizeof k)
    std::memcpy(reinterpret_cast<std::uint8_t*>(&part) + at, &k, sizeof k);
  tape_ring::close(ring, k);
}

bool is_part(const DeviceTape& part, std::uint32_t bytes, std::uint64_t k) {
  return bytes == sizeof part &&
         all_words_are(reinterpret_cast<const std::uint8_t*>(&part), sizeof part, k);
}

template <class Ring = StepTapeRing>
std::unique_ptr<Ring> fresh_ring() {
  auto ring = std::make_unique<Ring>();
  tape_ring::init(*ring, 1, 1);
  return ring;
}

template <class Ring>
void a_lapped_reader_never_keeps_a_mixed_part_and_reads_in_order() {
  const auto ring = fresh_ring<Ring>();
  constexpr std::uint64_t kRing = Ring::kPartCount;
  constexpr std::uint64_t kParts = 100 * kRing;
  std::atomic<bool> done{false};
  std::uint64_t copied = 0, laps = 0, mixed = 0, out_of_order = 0;
  std::thread reader([&] {
    const auto part = std::make_unique<typename Ring::PartType>();
    std::uint64_t cursor = 0;
    // The reader trails the writer by almost the whole ring, so that the writer often
    // replaces the part it is copying; once it stops until the writer has lapped it, as
    // a reader asleep for a while would find.
    bool stopped = false;
    for (;;) {
      const bool last_look = done.load(std::memory_order_acquire);
      std::uint64_t behind = kRing - 1;
      if (!stopped && cursor >= kRing / 2) {
        behind = kRing + 1;
        stopped = true;
      }
      while (tape_ring::head(*ring) < cursor + behind && !done.load(std::memory_order_acquire))
        std::this_thread::yield();
      std::uint32_t bytes = 0;
      switch (tape_ring::read(*ring, cursor, *part, bytes)) {
        case tape_ring::Read::kCopied:
          ++copied;
          // A part of another k whole is out of order, anything else mixed.
          if (!is_part(*part, bytes, cursor))
            ++(is_part(*part, bytes, cursor - 1) || is_part(*part, bytes, cursor + kRing)
                   ? out_of_order
                   : mixed);
          ++cursor;
          continue;
        case tape_ring::Read::kOverwritten:
          ++laps;
          cursor = tape_ring::resume_after_lap(*ring, cursor);
          continue;
        case tape_ring::Read::kNotYet:
          if (last_look) return;
          std::this_thread::yield();
      }
    }
  });
  for (std::uint64_t k = 0; k < kParts; ++k) write_part(*ring, k);
  done.store(true, std::memory_order_release);
  reader.join();
  EXPECT_EQ(mixed, 0u) << "parts copied while the writer replaced them, kept";
  EXPECT_EQ(out_of_order, 0u);
  EXPECT_GT(laps, 0u) << "the writer lapped a stopped reader: it must have found out";
  EXPECT_GE(copied, kRing / 2) << "the parts kept after its last lap at least";
  EXPECT_EQ(tape_ring::head(*ring), kParts);
}

TEST(TapeRing, AReaderLappedByTheWriterNeverKeepsAMixedPartAndReadsInOrder) {
  a_lapped_reader_never_keeps_a_mixed_part_and_reads_in_order<StepTapeRing>();
}

TEST(TapeRing, ADevicesRingTooNeverGivesAMixedPartOrOneOutOfOrder) {
  a_lapped_reader_never_keeps_a_mixed_part_and_reads_in_order<DeviceTapeRing>();
}

TEST(TapeRing, ALappedReaderStartsAgainAQuarterOfTheRingPastTheOldestPartKept) {
  const auto ring = fresh_ring();
  const std::uint64_t written = kStepTapeRingParts + 10;
  for (std::uint64_t k = 0; k < written; ++k) write_part(*ring, k);
  const auto part = std::make_unique<StepTape>();
  std::uint32_t bytes = 0;
  EXPECT_EQ(tape_ring::read(*ring, 0, *part, bytes), tape_ring::Read::kOverwritten);
  EXPECT_EQ(tape_ring::read(*ring, 9, *part, bytes), tape_ring::Read::kOverwritten);
  EXPECT_EQ(tape_ring::read(*ring, 10, *part, bytes), tape_ring::Read::kCopied)
      << "the oldest kept";
  const std::uint64_t resumed = tape_ring::resume_after_lap(*ring, 0);
  EXPECT_EQ(resumed, written - (kStepTapeRingParts - kStepTapeRingParts / 4));
  ASSERT_EQ(tape_ring::read(*ring, resumed, *part, bytes), tape_ring::Read::kCopied);
  EXPECT_TRUE(is_part(*part, bytes, resumed));
  EXPECT_EQ(tape_ring::read(*ring, written, *part, bytes), tape_ring::Read::kNotYet);
  // Whatever the ring says of itself (a count behind the reader's), a lapped reader
  // moves on.
  ring->written.store(3);
  EXPECT_EQ(tape_ring::resume_after_lap(*ring, 40), 41u);
}

TEST(TapeRing, APartNeverClosedIsNotReadAndAPartClaimingTooMuchIsCopiedWithinItsSize) {
  const auto ring = fresh_ring();
  write_part(*ring, 0);
  // The writer dies after opening part 1 and writing some of it.
  StepTape& torn = tape_ring::open(*ring, 1);
  torn.header.sim_step = 1;
  torn.data_bytes = 10;
  const auto part = std::make_unique<StepTape>();
  std::uint32_t bytes = 0;
  ASSERT_EQ(tape_ring::read(*ring, 0, *part, bytes), tape_ring::Read::kCopied);
  for (int look = 0; look < 3; ++look)
    EXPECT_EQ(tape_ring::read(*ring, 1, *part, bytes), tape_ring::Read::kNotYet);
  // A whole part whose header claims more data than a part holds.
  torn.data_bytes = 0xffffffffU;
  tape_ring::close(*ring, 1);
  ASSERT_EQ(tape_ring::read(*ring, 1, *part, bytes), tape_ring::Read::kCopied);
  EXPECT_EQ(bytes, sizeof(StepTape));
}

}  // namespace
}  // namespace afhub
