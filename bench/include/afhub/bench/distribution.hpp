// A latency distribution as `afhub bench` reports it: percentiles, maximum and
// sample count, by afhub's one rule (nearest rank, rt/percentile.hpp). From raw
// samples the percentiles are exact; from a histogram (loop wake-up latency,
// cyclictest) they are within its resolution (latency_histogram.hpp).
#pragma once

#include <cstdint>
#include <vector>

#include "afhub/rt/latency_histogram.hpp"

namespace afhub::bench {

struct Distribution {
  double p50_us = 0.0, p90_us = 0.0, p99_us = 0.0, p999_us = 0.0, max_us = 0.0;
  std::uint64_t samples = 0;
};

// All zero when there are no samples.
Distribution summarize(std::vector<double> samples_us);
Distribution summarize(const LatencyHistogram& histogram);

}  // namespace afhub::bench
