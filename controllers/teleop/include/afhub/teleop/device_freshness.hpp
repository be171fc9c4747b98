// Whether a device's samples stopped coming, judged on the teleoperation loop's own
// cycles. A device is stale once its newest sample is older than stale_ns and the loop
// has also run stale_ns worth of its own cycles since that sample came: on a busy
// machine the loop and the driver are descheduled together, and when they run again
// the loop's next cycles see new samples; only a driver that stopped (or hangs) while
// the loop runs makes its device stale.
#pragma once

#include <cstdint>

namespace afhub::teleop {

// Whether the loop itself stood still (stopped, starved) between two of its cycles
// `gap_ns` apart: past the stale time, and past two of its periods, so that a loop slower
// than the stale time, or one cycle late, is not taken for stopped.
bool stood_still(std::int64_t gap_ns, std::int64_t stale_ns, std::int64_t period_ns) noexcept;

class DeviceFreshness {
 public:
  // `period_ns`: the loop's period, by which stale_ns becomes a number of cycles.
  DeviceFreshness(std::int64_t stale_ns, std::int64_t period_ns) noexcept;

  // Once per cycle with the newest sample's publish stamp: true while it is stale.
  bool stale(std::int64_t sample_stamp_ns, std::int64_t now_ns) noexcept;

 private:
  std::int64_t stale_ns_;
  std::int64_t stale_cycles_;
  std::int64_t sample_stamp_ns_{0};
  std::int64_t cycles_since_sample_{0};
};

}  // namespace afhub::teleop
