// Sends pose frames to one WebSocket client from a thread of its own, so that a
// client that reads slowly, or not at all, delays nobody but itself. It holds one
// waiting frame: a newer frame replaces it (newest wins), so a slow client skips
// frames and the memory held for it never grows. When a write fails (the client
// left, or stopped reading past the server's write timeout) the client is dropped:
// no more frames are sent to it.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace afhub::viewer {

class FrameSender {
 public:
  // `write` sends one frame and returns whether it was sent whole; it may block.
  using Write = std::function<bool(const std::uint8_t* data, std::size_t size)>;
  explicit FrameSender(Write write);
  // Stops the thread, after the write in progress (if any) returns.
  ~FrameSender();
  FrameSender(const FrameSender&) = delete;
  FrameSender& operator=(const FrameSender&) = delete;

  // Hands the newest frame over, replacing the one still waiting; never blocks on
  // the client. Returns false once the client is dropped.
  bool offer(const std::vector<std::uint8_t>& frame);
  bool dropped();
  // Frames written, and frames replaced before they were written.
  std::uint64_t sent();
  std::uint64_t skipped();

 private:
  void run();

  Write write_;
  std::mutex mutex_;  // guards everything below but sending_
  std::condition_variable wake_;
  std::vector<std::uint8_t> waiting_;
  bool has_waiting_ = false;
  bool stop_ = false;
  bool dropped_ = false;
  std::uint64_t sent_ = 0, skipped_ = 0;
  std::vector<std::uint8_t> sending_;  // the sender thread's own
  std::thread thread_;                 // last: starts once the rest is built
};

}  // namespace afhub::viewer
