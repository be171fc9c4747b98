// The physics loop's achieved step rate: steps over about a second of running time.
// Time spent paused is in no window, and a resume or a world reset starts a new
// one, so the rate read after a pause is the rate the steps run at, not the steps
// over a second that was mostly paused (which read 168 Hz at 1 kHz).
#pragma once

#include <cstdint>

namespace afhub::physics {

class RateMeter {
 public:
  explicit RateMeter(std::int64_t window_ns = 1'000'000'000) : window_ns_(window_ns) {}

  // Once per loop cycle: the time, the steps taken so far, and whether the world
  // runs (not paused).
  void update(std::int64_t now_ns, std::uint64_t steps, bool running) noexcept {
    running_ = running;
    if (!running) {
      open_ = false;
      return;
    }
    if (!open_) {
      start(now_ns, steps);
      return;
    }
    if (now_ns - start_ns_ < window_ns_) return;
    rate_hz_ =
        static_cast<double>(steps - start_steps_) * 1e9 / static_cast<double>(now_ns - start_ns_);
    start(now_ns, steps);
  }
  // A world reset: the window open now mixes two worlds' steps; start again.
  void restart() noexcept { open_ = false; }

  // Steps per second over the last full window of running; 0 while paused and
  // before the first window closes.
  double rate_hz() const noexcept { return running_ ? rate_hz_ : 0.0; }

 private:
  void start(std::int64_t now_ns, std::uint64_t steps) noexcept {
    open_ = true;
    start_ns_ = now_ns;
    start_steps_ = steps;
  }

  std::int64_t window_ns_;
  bool open_ = false, running_ = true;
  std::int64_t start_ns_ = 0;
  std::uint64_t start_steps_ = 0;
  double rate_hz_ = 0.0;
};

}  // namespace afhub::physics
