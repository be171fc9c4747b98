// Loop measurements into a stats payload (see loop_timing.hpp).
#include "afhub/rt/loop_timing.hpp"

namespace afhub {

DurationPercentiles percentiles_of(const LatencyHistogram& histogram) noexcept {
  return {histogram.percentile_us(0.50), histogram.percentile_us(0.99),
          histogram.percentile_us(0.999), histogram.max_us()};
}

void LoopTiming::fill(LoopStats& stats) const noexcept {
  stats.cycles = cycles_;
  stats.overruns = overruns_;
  stats.late_commands = late_;
  stats.wake_latency = percentiles_of(wake_latency_);
  stats.compute = percentiles_of(compute_);
}

}  // namespace afhub
