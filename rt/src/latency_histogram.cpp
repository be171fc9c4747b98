// Percentiles of the log-linear histogram (see latency_histogram.hpp).
#include "afhub/rt/latency_histogram.hpp"

#include "afhub/rt/percentile.hpp"

namespace afhub {

std::int64_t LatencyHistogram::percentile_ns(double q) const noexcept {
  const std::uint64_t rank = percentile_rank(count_, q);
  if (rank == 0) return 0;
  std::uint64_t seen = 0;
  std::size_t block = 0;
  while (block < blocks_.size() && seen + blocks_[block] < rank) seen += blocks_[block++];
  if (block == blocks_.size()) return max_ns_;  // among the overflow
  for (std::size_t bin = block * kSubBins;; ++bin)
    if ((seen += bins_[bin]) >= rank) return std::min(highest_ns(bin), max_ns_);
}

}  // namespace afhub
