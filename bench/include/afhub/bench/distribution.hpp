// A latency distribution as `afhub bench` reports it: percentiles, maximum and
// sample count. From raw samples the percentiles are exact (nearest rank); from a
// 1 us histogram (loop wake-up latency, cyclictest) they are bin upper edges.
#pragma once

#include <cstdint>
#include <vector>

#include "afhub/rt/latency_histogram.hpp"

namespace afhub::bench {

struct Distribution {
  double p50_us = 0.0, p90_us = 0.0, p99_us = 0.0, p999_us = 0.0, max_us = 0.0;
  std::uint64_t samples = 0;
};

// The smallest sample with at least q of all samples at or below it (0 < q <= 1).
// `sorted` is in increasing order and not empty.
double nearest_rank(const std::vector<double>& sorted, double q);

// All zero when there are no samples.
Distribution summarize(std::vector<double> samples_us);
Distribution summarize(const LatencyHistogram& histogram);

}  // namespace afhub::bench
