// A device's staleness on the loop's own cycles (see device_freshness.hpp).
#include "afhub/teleop/device_freshness.hpp"

#include <algorithm>

namespace afhub::teleop {

bool stood_still(std::int64_t gap_ns, std::int64_t stale_ns, std::int64_t period_ns) noexcept {
  return gap_ns > stale_ns && gap_ns > 2 * period_ns;
}

DeviceFreshness::DeviceFreshness(std::int64_t stale_ns, std::int64_t period_ns) noexcept
    : stale_ns_(stale_ns),
      stale_cycles_(std::max<std::int64_t>(
          1, (stale_ns + period_ns - 1) / std::max<std::int64_t>(1, period_ns))) {}

bool DeviceFreshness::stale(std::int64_t sample_stamp_ns, std::int64_t now_ns) noexcept {
  if (sample_stamp_ns != sample_stamp_ns_) {
    sample_stamp_ns_ = sample_stamp_ns;
    cycles_since_sample_ = 0;
    return false;
  }
  ++cycles_since_sample_;
  return now_ns - sample_stamp_ns > stale_ns_ && cycles_since_sample_ >= stale_cycles_;
}

}  // namespace afhub::teleop
