// Ages in microseconds, counted into fixed bins (made once: recording never
// allocates), for the bridge's --latency report.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace afhub::bridges {

class AgeHistogram {
 public:
  // 1 us bins up to 100 ms; older ages count in the last bin (and in max).
  AgeHistogram() : bins_(100'000, 0) {}

  void record(std::int64_t age_ns) noexcept {
    const std::int64_t us = std::max<std::int64_t>(0, age_ns / 1000);
    ++bins_[static_cast<std::size_t>(std::min<std::int64_t>(us, bins_.size() - 1))];
    max_us_ = std::max(max_us_, us);
    ++count_;
  }
  std::uint64_t count() const noexcept { return count_; }
  std::int64_t max_us() const noexcept { return max_us_; }
  // The age below which `fraction` of the recorded ones fall, in us.
  std::int64_t quantile_us(double fraction) const noexcept {
    const auto wanted = static_cast<std::uint64_t>(fraction * static_cast<double>(count_));
    std::uint64_t seen = 0;
    for (std::size_t us = 0; us < bins_.size(); ++us) {
      seen += bins_[us];
      if (seen > wanted) return static_cast<std::int64_t>(us);
    }
    return max_us_;
  }

 private:
  std::vector<std::uint32_t> bins_;
  std::int64_t max_us_ = 0;
  std::uint64_t count_ = 0;
};

}  // namespace afhub::bridges
