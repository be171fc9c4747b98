// The latest-value slot protocol on its own (hub/client/src/latest_slot.hpp): a writer
// thread updating in place and reader threads copying out never see a mixed update;
// a writer stopped mid-update leaves a slot readers call torn; a reader asleep on
// one or several slots wakes on an update. Built twice: with the unit tests (under
// ASan and UBSan) and alone under ThreadSanitizer (latest_slot_tsan).
#include "latest_slot.hpp"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

namespace afhub {
namespace {

// A payload whose words all carry the update's number: a copy mixing two updates
// has words that differ.
struct Words {
  std::array<std::uint64_t, 96> word{};
};

struct TestSlot {
  SlotControl control;
  Words payload;
};

void write(TestSlot& slot, std::uint64_t value) {
  slot::begin_update(slot.control, sizeof slot.payload);
  for (std::uint64_t& word : slot.payload.word) word = value;
  slot::end_update(slot.control, static_cast<std::int64_t>(value));
}

slot::Read read(const TestSlot& slot, Words& copy, std::uint32_t& observed) {
  std::uint32_t copied = 0;
  const slot::Read result =
      slot::read(slot.control, &slot.payload, sizeof copy, &copy, observed, copied);
  if (result == slot::Read::kCopied) {
    EXPECT_EQ(copied, sizeof copy);
  }
  return result;
}

TEST(LatestSlot, ReadersNeverSeeAMixedUpdate) {
  TestSlot slot;
  slot::init(slot.control);
  write(slot, 1);
  constexpr std::uint64_t kUpdates = 200'000;
  std::atomic<bool> done{false};
  std::atomic<std::uint64_t> mixed{0}, copies{0}, backwards{0};
  // The writer starts once both readers hold a first copy: on a loaded machine (the
  // sanitizer phase of CI) it once wrote every update before a reader had run.
  std::atomic<int> reading{0};
  std::vector<std::thread> readers;
  for (int r = 0; r < 2; ++r)
    readers.emplace_back([&] {
      std::uint32_t observed = ~0U;
      std::uint64_t last = 0;
      Words copy;
      bool counted = false;
      while (!done.load(std::memory_order_acquire)) {
        if (read(slot, copy, observed) != slot::Read::kCopied) continue;
        copies.fetch_add(1, std::memory_order_relaxed);
        if (!counted) reading.fetch_add(1);
        counted = true;
        for (std::uint64_t word : copy.word)
          if (word != copy.word[0]) {
            mixed.fetch_add(1, std::memory_order_relaxed);
            break;
          }
        if (copy.word[0] < last) backwards.fetch_add(1, std::memory_order_relaxed);
        last = copy.word[0];
      }
    });
  while (reading.load() < 2) std::this_thread::yield();
  for (std::uint64_t value = 2; value <= kUpdates; ++value) write(slot, value);
  done.store(true, std::memory_order_release);
  for (std::thread& reader : readers) reader.join();
  EXPECT_EQ(mixed.load(), 0U) << "copies that mixed two updates";
  EXPECT_EQ(backwards.load(), 0U) << "copies older than a copy before them";
  EXPECT_GT(copies.load(), 0U);
  EXPECT_EQ(slot.control.sequence.load(), 2 * kUpdates) << "two per update";
}

TEST(LatestSlot, AnUnchangedSlotIsNotCopiedAgain) {
  TestSlot slot;
  slot::init(slot.control);
  write(slot, 7);
  std::uint32_t observed = ~0U;
  Words copy;
  EXPECT_EQ(read(slot, copy, observed), slot::Read::kCopied);
  EXPECT_EQ(copy.word[5], 7U);
  EXPECT_EQ(read(slot, copy, observed), slot::Read::kUnchanged);
  write(slot, 8);
  EXPECT_EQ(read(slot, copy, observed), slot::Read::kCopied);
  EXPECT_EQ(copy.word[95], 8U);
}

// An update shorter than its slot (a state of fewer joints) is copied at its length.
TEST(LatestSlot, AReaderCopiesTheBytesTheUpdateWrote) {
  TestSlot slot;
  slot::init(slot.control);
  Words copy;
  copy.word.fill(9);
  slot::begin_update(slot.control, 3 * sizeof(std::uint64_t));
  for (std::size_t i = 0; i < 3; ++i) slot.payload.word[i] = 1;
  slot::end_update(slot.control, 1);
  std::uint32_t observed = ~0U, copied = 0;
  ASSERT_EQ(slot::read(slot.control, &slot.payload, sizeof copy, &copy, observed, copied),
            slot::Read::kCopied);
  EXPECT_EQ(copied, 3 * sizeof(std::uint64_t));
  EXPECT_EQ(copy.word[2], 1U);
  EXPECT_EQ(copy.word[3], 9U) << "copied past the update";
  // Never past the reader's capacity, whatever the slot claims.
  slot::begin_update(slot.control, 1'000'000);
  slot::end_update(slot.control, 2);
  ASSERT_EQ(slot::read(slot.control, &slot.payload, sizeof copy, &copy, observed, copied),
            slot::Read::kCopied);
  EXPECT_EQ(copied, sizeof copy);
}

TEST(LatestSlot, AnUpdateNeverEndedIsTornUntilTheNextWriterEndsOne) {
  TestSlot slot;
  slot::init(slot.control);
  write(slot, 3);
  std::uint32_t observed = ~0U;
  Words copy;
  ASSERT_EQ(read(slot, copy, observed), slot::Read::kCopied);
  // The writer dies after begin_update: half its payload written.
  slot::begin_update(slot.control, sizeof slot.payload);
  for (std::size_t i = 0; i < 40; ++i) slot.payload.word[i] = 4;
  EXPECT_EQ(read(slot, copy, observed), slot::Read::kTorn);
  EXPECT_EQ(observed & 1U, 1U) << "a reader remembers the torn sequence";
  EXPECT_EQ(read(slot, copy, observed), slot::Read::kTorn)
      << "and says it again at the cost of one load";
  // A wait on it sleeps (until its timeout) rather than spin on the torn slot.
  const slot::Watch watch{&slot.control, observed};
  const auto before = std::chrono::steady_clock::now();
  slot::wait({&watch, 1}, 20'000'000);
  EXPECT_GE(std::chrono::steady_clock::now() - before, std::chrono::milliseconds(19));
  // begin_update again (a writer that resumes the slot) keeps it odd; ending it gives a
  // whole update.
  slot::begin_update(slot.control, sizeof slot.payload);
  for (std::uint64_t& word : slot.payload.word) word = 5;
  slot::end_update(slot.control, 5);
  EXPECT_EQ(read(slot, copy, observed), slot::Read::kCopied);
  EXPECT_EQ(copy.word[0], 5U);
  EXPECT_EQ(copy.word[95], 5U);
}

// A reader asleep on slots wakes when one of them is updated: one slot (FUTEX_WAIT)
// and four (futex_waitv). The wait's timeout is a minute: a lost wake-up fails the
// check below, which a wake-up in time passes by three orders of magnitude.
void expect_wakes_on_update(std::size_t slots, std::size_t updated) {
  std::vector<TestSlot> slot(slots);
  std::vector<slot::Watch> watches;
  for (TestSlot& each : slot) {
    slot::init(each.control);
    write(each, 1);
    watches.push_back({&each.control, each.control.sequence.load()});
  }
  std::atomic<bool> woke{false};
  std::thread waiter([&] {
    slot::wait(watches, 60'000'000'000);
    woke.store(true);
  });
  // Until the waiter sleeps: it has set the flag the writer looks at.
  while (slot[updated].control.sleeping.load() == 0) std::this_thread::yield();
  const auto before = std::chrono::steady_clock::now();
  write(slot[updated], 2);
  waiter.join();
  EXPECT_TRUE(woke.load());
  EXPECT_LT(std::chrono::steady_clock::now() - before, std::chrono::seconds(30))
      << "the wake-up was lost: the wait ran to its timeout";
  EXPECT_EQ(slot[updated].control.sleeping.load(), 0U) << "the writer cleared the flag";
}

TEST(LatestSlot, ASleepingReaderWakesOnAnUpdateOfItsSlot) {
  expect_wakes_on_update(1, 0);
}

TEST(LatestSlot, ASleepingReaderWakesOnAnUpdateOfAnyOfItsSlots) {
  expect_wakes_on_update(4, 2);
}

TEST(LatestSlot, AWaitOnAChangedSlotReturnsAtOnce) {
  TestSlot slot;
  slot::init(slot.control);
  write(slot, 1);
  const slot::Watch stale{&slot.control, 0};  // before the update
  const auto before = std::chrono::steady_clock::now();
  slot::wait({&stale, 1}, 60'000'000'000);
  EXPECT_LT(std::chrono::steady_clock::now() - before, std::chrono::seconds(30));
}

}  // namespace
}  // namespace afhub
