// A histogram of durations for the loops' timing (and every other latency afhub
// reports): real-time safe, as record() is a few instructions on fixed storage (no
// allocation, no system call), and small: 30 KiB whatever it counts.
//
// Its bins are log-linear, as HdrHistogram's: 1 ns wide below 256 ns, then each power
// of two [2^k, 2^(k+1)) cut into 128 bins of 2^(k-7) ns. A percentile (the rule of
// percentile.hpp) reads the highest value of the bin that holds it, capped at the
// exact maximum (kept apart): never below the exact percentile of the same samples
// and less than 1/128 (0.8 %) above it. Up to kLimitNs (68.7 s); samples beyond
// count as overflow, and a percentile among them reads the maximum.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>

namespace afhub {

class LatencyHistogram {
 public:
  static constexpr int kSubBits = 7;  // 2^7 = 128 bins per power of two: 1/128 resolution
  static constexpr std::int64_t kSubBins = std::int64_t{1} << kSubBits;
  static constexpr int kLimitBits = 36;
  static constexpr std::int64_t kLimitNs = std::int64_t{1} << kLimitBits;       // 68.7 s
  static constexpr std::size_t kBins = (kLimitBits - kSubBits + 1) * kSubBins;  // 3840

  // Counts `ns` (`times` over). A negative duration (stamps of two machines' clocks)
  // counts as 0.
  void record(std::int64_t ns, std::uint64_t times = 1) noexcept {
    ns = std::max<std::int64_t>(ns, 0);
    if (ns < kLimitNs) {
      const std::size_t bin = bin_of(ns);
      bins_[bin] += times;
      blocks_[bin / kSubBins] += times;
    } else {
      overflow_ += times;
    }
    count_ += times;
    max_ns_ = std::max(max_ns_, ns);
  }

  std::uint64_t count() const noexcept { return count_; }
  std::uint64_t overflow() const noexcept { return overflow_; }  // samples of kLimitNs or more
  std::int64_t max_ns() const noexcept { return max_ns_; }
  double max_us() const noexcept { return static_cast<double>(max_ns_) * 1e-3; }

  // The q-quantile (0 < q <= 1), or 0 when empty. It reads the sums of 128 bins first,
  // then 128 bins: a loop reads its percentiles each second in about a microsecond.
  std::int64_t percentile_ns(double q) const noexcept;
  double percentile_us(double q) const noexcept {
    return static_cast<double>(percentile_ns(q)) * 1e-3;
  }

  // The bins, to print or merge them: bin i holds lowest_ns(i) to highest_ns(i).
  std::uint64_t bin_count(std::size_t bin) const noexcept { return bin < kBins ? bins_[bin] : 0; }
  static constexpr std::size_t bin_of(std::int64_t ns) noexcept {
    if (ns < 2 * kSubBins) return static_cast<std::size_t>(ns);
    const int shift = std::bit_width(static_cast<std::uint64_t>(ns)) - 1 - kSubBits;
    return static_cast<std::size_t>(shift * kSubBins + (ns >> shift));
  }
  static constexpr std::int64_t lowest_ns(std::size_t bin) noexcept {
    const int shift = shift_of(bin);
    return (static_cast<std::int64_t>(bin) - shift * kSubBins) << shift;
  }
  static constexpr std::int64_t highest_ns(std::size_t bin) noexcept {
    return lowest_ns(bin) + (std::int64_t{1} << shift_of(bin)) - 1;
  }

 private:
  static constexpr int shift_of(std::size_t bin) noexcept {
    return std::max(0, static_cast<int>(static_cast<std::int64_t>(bin) / kSubBins) - 1);
  }

  std::array<std::uint64_t, kBins> bins_{};
  std::array<std::uint64_t, kBins / kSubBins> blocks_{};  // the sums of kSubBins bins each
  std::uint64_t overflow_ = 0;
  std::uint64_t count_ = 0;
  std::int64_t max_ns_ = 0;
};

}  // namespace afhub
