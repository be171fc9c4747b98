// One WebSocket client's sender (see frame_sender.hpp).
#include "afhub/viewer/frame_sender.hpp"

namespace afhub::viewer {

FrameSender::FrameSender(Write write) : write_(std::move(write)), thread_([this] { run(); }) {}

FrameSender::~FrameSender() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

bool FrameSender::offer(const std::vector<std::uint8_t>& frame) {
  {
    std::lock_guard lock(mutex_);
    if (dropped_) return false;
    if (has_waiting_) ++skipped_;
    waiting_.assign(frame.begin(), frame.end());  // reuses the capacity: no allocation
    has_waiting_ = true;
  }
  wake_.notify_one();
  return true;
}

bool FrameSender::dropped() {
  std::lock_guard lock(mutex_);
  return dropped_;
}

std::uint64_t FrameSender::sent() {
  std::lock_guard lock(mutex_);
  return sent_;
}

std::uint64_t FrameSender::skipped() {
  std::lock_guard lock(mutex_);
  return skipped_;
}

void FrameSender::run() {
  std::unique_lock lock(mutex_);
  while (true) {
    wake_.wait(lock, [this] { return stop_ || has_waiting_; });
    if (stop_) return;
    waiting_.swap(sending_);  // both keep their capacity
    has_waiting_ = false;
    lock.unlock();
    const bool whole = write_(sending_.data(), sending_.size());
    lock.lock();
    if (!whole) {
      dropped_ = true;
      return;
    }
    ++sent_;
  }
}

}  // namespace afhub::viewer
