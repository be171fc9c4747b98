// Percentiles of measured latencies (see distribution.hpp).
#include "afhub/bench/distribution.hpp"

#include <algorithm>
#include <span>

#include "afhub/rt/percentile.hpp"

namespace afhub::bench {

Distribution summarize(std::vector<double> samples_us) {
  Distribution out;
  if (samples_us.empty()) return out;
  std::sort(samples_us.begin(), samples_us.end());
  const std::span<const double> sorted = samples_us;
  out.p50_us = percentile_of_sorted(sorted, 0.50);
  out.p90_us = percentile_of_sorted(sorted, 0.90);
  out.p99_us = percentile_of_sorted(sorted, 0.99);
  out.p999_us = percentile_of_sorted(sorted, 0.999);
  out.max_us = samples_us.back();
  out.samples = samples_us.size();
  return out;
}

Distribution summarize(const LatencyHistogram& histogram) {
  Distribution out;
  out.p50_us = histogram.percentile_us(0.50);
  out.p90_us = histogram.percentile_us(0.90);
  out.p99_us = histogram.percentile_us(0.99);
  out.p999_us = histogram.percentile_us(0.999);
  out.max_us = histogram.max_us();
  out.samples = histogram.count();
  return out;
}

}  // namespace afhub::bench
