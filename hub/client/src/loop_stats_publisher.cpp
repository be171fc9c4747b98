// The stats channel of a loop (see loop_stats_publisher.hpp).
#include "afhub/hub/loop_stats_publisher.hpp"

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"

namespace afhub {

LoopStatsPublisher::LoopStatsPublisher(const std::string& name, const std::string& body,
                                       std::int64_t period_ns, bool lockstep,
                                       const RealtimeGrant& grant)
    : writer_({std::string(kService), runtime_name(), std::string(kStatsEvent)}) {
  set_name(identity_.name, name);
  set_name(identity_.body, body);
  identity_.period_s = lockstep ? 0.0 : static_cast<double>(period_ns) * 1e-9;
  identity_.lockstep = lockstep;
  identity_.realtime = grant.realtime;
  identity_.memory_locked = grant.memory_locked;
  identity_.cpu = grant.cpu;
  identity_.cpu_wake_latency_us = grant.cpu_wake_latency_us;
}

void LoopStatsPublisher::maybe_publish(std::int64_t now_ns, const LoopTiming& timing) noexcept {
  if (last_ns_ == 0) {
    last_ns_ = now_ns;
    return;
  }
  if (now_ns - last_ns_ < 1'000'000'000) return;
  LoopStats* stats = writer_.loan();
  if (!stats) return;  // shared memory exhausted: try again next cycle
  const PayloadHeader header = stats->header;
  *stats = identity_;
  stats->header = header;
  timing.fill(*stats);
  stats->rate_hz = static_cast<double>(timing.cycles() - last_cycles_) * 1e9 /
                   static_cast<double>(now_ns - last_ns_);
  last_cycles_ = timing.cycles();
  last_ns_ = now_ns;
  writer_.publish(stats);
}

}  // namespace afhub
