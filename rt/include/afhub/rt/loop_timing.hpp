// What a loop measures about itself: wake-up latency and compute time per cycle in
// fixed-size histograms, and counts of cycles, overruns and late commands.
// Recording is real-time safe (no allocation, no system call).
#pragma once

#include <cstdint>

#include "afhub/rt/latency_histogram.hpp"
#include "afhub/shm_layout/loop_stats.hpp"

namespace afhub {

class LoopTiming {
 public:
  void record(std::int64_t wake_latency_ns, std::int64_t compute_ns) noexcept {
    wake_latency_.record(wake_latency_ns);
    compute_.record(compute_ns);
    ++cycles_;
  }
  void count_overruns(std::uint64_t periods) noexcept { overruns_ += periods; }
  void count_late(std::uint64_t commands) noexcept { late_ += commands; }
  // The time a cycle spent after its work (publishing statistics, saying events):
  // outside the compute time, but counted here, not lost.
  void record_housekeeping(std::int64_t ns) noexcept {
    housekeeping_total_ns_ += ns;
    if (ns > housekeeping_max_ns_) housekeeping_max_ns_ = ns;
  }

  std::uint64_t cycles() const { return cycles_; }
  std::uint64_t overruns() const { return overruns_; }
  std::uint64_t late_commands() const { return late_; }
  std::int64_t housekeeping_max_ns() const { return housekeeping_max_ns_; }
  std::int64_t housekeeping_total_ns() const { return housekeeping_total_ns_; }
  const LatencyHistogram& wake_latency() const { return wake_latency_; }
  const LatencyHistogram& compute() const { return compute_; }

  // Counts and percentiles since the start into a stats payload.
  void fill(LoopStats& stats) const noexcept;

 private:
  LatencyHistogram wake_latency_;
  LatencyHistogram compute_;
  std::uint64_t cycles_ = 0, overruns_ = 0, late_ = 0;
  std::int64_t housekeeping_max_ns_ = 0, housekeeping_total_ns_ = 0;
};

DurationPercentiles percentiles_of(const LatencyHistogram& histogram) noexcept;

}  // namespace afhub
