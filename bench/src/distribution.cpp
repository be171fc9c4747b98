// Percentiles of measured latencies (see distribution.hpp).
#include "afhub/bench/distribution.hpp"

#include <algorithm>
#include <cmath>

namespace afhub::bench {

double nearest_rank(const std::vector<double>& sorted, double q) {
  const auto n = static_cast<double>(sorted.size());
  const auto rank = static_cast<std::size_t>(std::ceil(q * n - 1e-9));
  return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

Distribution summarize(std::vector<double> samples_us) {
  Distribution out;
  if (samples_us.empty()) return out;
  std::sort(samples_us.begin(), samples_us.end());
  out.p50_us = nearest_rank(samples_us, 0.50);
  out.p90_us = nearest_rank(samples_us, 0.90);
  out.p99_us = nearest_rank(samples_us, 0.99);
  out.p999_us = nearest_rank(samples_us, 0.999);
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
