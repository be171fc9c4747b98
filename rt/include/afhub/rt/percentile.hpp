// afhub's one percentile rule, for every figure it prints or publishes (the loops'
// statistics and `afhub top`, the bench, teleop's and the DDS bridge's latencies):
// nearest rank. The q-quantile of N samples is the smallest sample with at least
// ceil(q * N) samples at or below it: p50 of {1, 2, 3, 4} is 2, p99 of 100 samples
// is the 99th smallest, p100 the largest. It is always a value that was measured
// (no interpolation between samples), so figures from samples and from a histogram
// (latency_histogram.hpp) read alike.
#pragma once

#include <cstdint>
#include <span>

namespace afhub {

// The 1-based rank of the q-quantile among `count` samples: ceil(q * count) within
// 1..count, and 0 when count is 0. q at or below 0 reads the smallest sample; q
// above 1, or NaN, the largest.
std::uint64_t percentile_rank(std::uint64_t count, double q) noexcept;

// The q-quantile of `sorted` (in increasing order) by that rule; T{} when empty.
template <typename T>
T percentile_of_sorted(std::span<const T> sorted, double q) noexcept {
  if (sorted.empty()) return T{};
  return sorted[percentile_rank(sorted.size(), q) - 1];
}

}  // namespace afhub
