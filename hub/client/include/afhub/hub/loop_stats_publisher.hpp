// Publishes a loop's timing on {"afhub", "<runtime name>", "stats"} once a second,
// where `afhub status` and `afhub top` find it. Needs connect_to_hub() first.
#pragma once

#include <cstdint>
#include <string>

#include "afhub/hub/channel.hpp"
#include "afhub/rt/loop_timing.hpp"
#include "afhub/rt/periodic_loop.hpp"

namespace afhub {

class LoopStatsPublisher {
 public:
  LoopStatsPublisher(const std::string& name, const std::string& body, std::int64_t period_ns,
                     bool lockstep, const RealtimeGrant& grant);
  // Publishes when a second has passed since the last time.
  void maybe_publish(std::int64_t now_ns, const LoopTiming& timing) noexcept;

 private:
  LoopStats identity_;  // the fields that never change
  Writer<LoopStats> writer_;
  std::int64_t last_ns_ = 0;
  std::uint64_t last_cycles_ = 0;
};

}  // namespace afhub
