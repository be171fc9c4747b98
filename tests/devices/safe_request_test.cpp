// Making a device safe from another thread than its loop's (safe_request.hpp): the loop
// does it between two exchanges and never exchanges again; a loop stuck in an exchange
// leaves it to the requester; a request on the loop's own thread does not wait.
#include "afhub/devices/safe_request.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

namespace afhub::devices {
namespace {

// Records which thread made it safe, and whether that overlapped an exchange.
class WatchedDevice : public Device {
 public:
  DeviceSpec spec() const override { return {}; }
  DeviceSample exchange(const DeviceOutput&) override {
    ++inside;
    while (stuck) {
      held = true;
      std::this_thread::yield();
    }
    if (made_safe > 0) ++exchanges_after_safe;
    --inside;
    ++exchanges;
    return {};
  }
  void make_safe() noexcept override {
    if (inside > 0) ++overlaps;
    safe_thread = std::this_thread::get_id();
    ++made_safe;
  }
  std::atomic<int> inside{0}, exchanges{0}, made_safe{0}, overlaps{0}, exchanges_after_safe{0};
  std::atomic<bool> stuck{false};
  std::atomic<bool> held{false};  // an exchange saw `stuck` and waits
  std::thread::id safe_thread;
};

// A device and its request, with a driver's loop in miniature on its own thread:
// serve, then exchange, until stopped.
struct RunningLoop {
  WatchedDevice device;
  SafeRequest request;
  std::atomic<bool> done{false};
  std::thread::id loop_thread;
  std::thread looping;

  RunningLoop() {
    request.attach(&device);
    looping = std::thread([this] {
      loop_thread = std::this_thread::get_id();
      while (!done) {
        if (!request.serve()) device.exchange({});
        std::this_thread::yield();
      }
    });
  }
  ~RunningLoop() { stop(); }
  void stop() {
    device.stuck = false;
    done = true;
    if (looping.joinable()) looping.join();
  }
};

constexpr std::int64_t kTimeoutNs = 5'000'000'000;  // far more than a running loop needs

TEST(SafeRequest, TheLoopMakesTheDeviceSafeBetweenExchangesAndStops) {
  RunningLoop running;
  WatchedDevice& device = running.device;
  while (device.exchanges < 100) std::this_thread::yield();
  EXPECT_EQ(running.request.request(kTimeoutNs), MadeSafeBy::kLoop);
  const int exchanges = device.exchanges;
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // the loop goes on serving
  running.stop();
  EXPECT_EQ(device.made_safe, 1);
  EXPECT_EQ(device.safe_thread, running.loop_thread);
  EXPECT_EQ(device.overlaps, 0);
  EXPECT_EQ(device.exchanges_after_safe, 0);
  EXPECT_EQ(device.exchanges, exchanges);
}

TEST(SafeRequest, ALoopStuckInAnExchangeLeavesItToTheRequester) {
  RunningLoop running;
  WatchedDevice& device = running.device;
  while (device.exchanges < 10) std::this_thread::yield();
  device.stuck = true;
  // Held, not merely inside: an exchange that read `stuck` just before it was set would
  // end, and the loop would then serve the request itself (seen once under ASan).
  while (!device.held) std::this_thread::yield();
  EXPECT_EQ(running.request.request(20'000'000), MadeSafeBy::kRequester);
  EXPECT_EQ(device.made_safe, 1);
  EXPECT_EQ(device.safe_thread, std::this_thread::get_id());
  const int exchanges = device.exchanges;
  device.stuck = false;  // the exchange under way ends; no other one starts
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  running.stop();
  EXPECT_EQ(device.exchanges, exchanges + 1);
  EXPECT_EQ(device.made_safe, 1);
}

TEST(SafeRequest, ARequestOnTheLoopsOwnThreadDoesNotWait) {
  WatchedDevice device;
  SafeRequest request;
  request.attach(&device);
  EXPECT_FALSE(request.serve());  // this thread is the loop's
  EXPECT_EQ(request.request(kTimeoutNs), MadeSafeBy::kRequesterOnLoopThread);
  EXPECT_EQ(device.made_safe, 1);
  EXPECT_TRUE(request.serve());  // and the loop leaves the device alone from then on
  EXPECT_EQ(device.made_safe, 1);
}

TEST(SafeRequest, WithNoDeviceARequestDoesNothing) {
  SafeRequest request;
  EXPECT_EQ(request.request(kTimeoutNs), MadeSafeBy::kNoDevice);
}

}  // namespace
}  // namespace afhub::devices
