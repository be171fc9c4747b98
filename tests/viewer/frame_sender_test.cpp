// A page's frame sender: a page whose writes block makes no one else wait, and
// while it blocks only the newest frame is kept for it (never a growing queue).
#include "afhub/viewer/frame_sender.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

namespace afhub::viewer {
namespace {

// A write that blocks until released, as to a page that stopped reading.
struct BlockingPage {
  std::mutex mutex;
  std::condition_variable changed;
  bool released = false;
  int writes_started = 0;
  std::vector<std::vector<std::uint8_t>> written;

  bool write(const std::uint8_t* data, std::size_t size) {
    std::unique_lock lock(mutex);
    ++writes_started;
    changed.notify_all();
    changed.wait(lock, [this] { return released; });
    written.emplace_back(data, data + size);
    changed.notify_all();
    return true;
  }
  void wait_for(const std::function<bool()>& condition) {
    std::unique_lock lock(mutex);
    changed.wait(lock, condition);
  }
};

std::vector<std::uint8_t> frame_number(std::uint8_t n) {
  return std::vector<std::uint8_t>(32, n);
}

TEST(FrameSender, ABlockedPageKeepsOnlyTheNewestFrameAndBlocksNoOne) {
  BlockingPage stuck;
  FrameSender stuck_sender(
      [&stuck](const std::uint8_t* data, std::size_t size) { return stuck.write(data, size); });
  std::vector<std::vector<std::uint8_t>> other_written;
  std::mutex other_mutex;
  FrameSender other_sender([&](const std::uint8_t* data, std::size_t size) {
    std::lock_guard lock(other_mutex);
    other_written.emplace_back(data, data + size);
    return true;
  });

  ASSERT_TRUE(stuck_sender.offer(frame_number(0)));
  stuck.wait_for([&] { return stuck.writes_started == 1; });  // frame 0 is stuck in its write
  // 200 more frames: offer() returns at once each time (a blocking one would hang here).
  for (int n = 1; n <= 200; ++n) {
    ASSERT_TRUE(stuck_sender.offer(frame_number(static_cast<std::uint8_t>(n))));
    other_sender.offer(frame_number(static_cast<std::uint8_t>(n)));
  }
  EXPECT_EQ(stuck_sender.skipped(), 199U) << "one frame waits; the older ones are replaced";
  EXPECT_EQ(stuck_sender.sent(), 0U);

  {
    std::lock_guard lock(stuck.mutex);
    stuck.released = true;
  }
  stuck.changed.notify_all();
  stuck.wait_for([&] { return stuck.written.size() == 2; });
  EXPECT_EQ(stuck.written[0], frame_number(0));
  EXPECT_EQ(stuck.written[1], frame_number(200)) << "the newest frame wins";
  // The other page got its frames meanwhile, up to the newest (a generous bound: not
  // a speed check, only no hang when it never comes).
  bool newest = false;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!newest && std::chrono::steady_clock::now() < until) {
    std::this_thread::yield();
    std::lock_guard lock(other_mutex);
    newest = !other_written.empty() && other_written.back() == frame_number(200);
  }
  EXPECT_TRUE(newest) << "the other page never got the newest frame";
}

TEST(FrameSender, AFailedWriteDropsThePage) {
  int writes = 0;
  FrameSender sender([&writes](const std::uint8_t*, std::size_t) {
    ++writes;
    return false;
  });
  EXPECT_TRUE(sender.offer(frame_number(1)));
  while (!sender.dropped()) std::this_thread::yield();
  EXPECT_FALSE(sender.offer(frame_number(2)));
  EXPECT_EQ(writes, 1);
}

}  // namespace
}  // namespace afhub::viewer
