// A preallocated histogram of durations in microseconds: 1 us bins up to 100 ms,
// anything above counted in the last bin (the exact maximum is kept apart).
// record() is real-time safe. A percentile reads the per-block sums first, then one
// block's bins (at most kBins / kBlock + kBlock reads, not kBins), so a loop may
// read its percentiles once a second without a long scan.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace afhub {

class LatencyHistogram {
 public:
  static constexpr std::size_t kBins = 100'000;
  static constexpr std::size_t kBlock = 316;  // about sqrt(kBins): the fewest reads

  LatencyHistogram() : bins_(kBins, 0), blocks_(kBins / kBlock + 1, 0) {}

  void record(double microseconds) noexcept {
    if (!(microseconds >= 0.0)) microseconds = 0.0;
    const auto bin = std::min(static_cast<std::size_t>(microseconds), kBins - 1);
    ++bins_[bin];
    ++blocks_[bin / kBlock];
    ++count_;
    max_us_ = std::max(max_us_, microseconds);
  }

  std::uint64_t count() const { return count_; }
  // Samples in [bin, bin + 1) us (the last bin: everything above).
  std::uint64_t bin_count(std::size_t bin) const { return bin < kBins ? bins_[bin] : 0; }
  double max_us() const { return max_us_; }

  // The upper edge of the bin holding the q-th quantile (0 < q <= 1), or 0 when empty.
  double percentile_us(double q) const {
    if (count_ == 0) return 0.0;
    const auto rank = static_cast<std::uint64_t>(q * static_cast<double>(count_ - 1)) + 1;
    std::uint64_t seen = 0;
    std::size_t block = 0;
    while (block + 1 < blocks_.size() && seen + blocks_[block] < rank) seen += blocks_[block++];
    for (std::size_t bin = block * kBlock; bin < kBins; ++bin) {
      seen += bins_[bin];
      if (seen >= rank) return std::min(static_cast<double>(bin + 1), max_us_);
    }
    return max_us_;
  }

 private:
  std::vector<std::uint64_t> bins_;
  std::vector<std::uint64_t> blocks_;  // sums of kBlock bins each
  std::uint64_t count_ = 0;
  double max_us_ = 0.0;
};

}  // namespace afhub
