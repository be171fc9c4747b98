// The hub's health channel: live processes and mempool usage, relayed from
// RouDi's introspection, plus uptime and body count, once a second.
#pragma once

#include <chrono>
#include <memory>

#include "afhub/hub/channel.hpp"
#include "afhub/shm_layout/health.hpp"

namespace afhub {

class HealthReporter {
 public:
  HealthReporter();
  ~HealthReporter();
  void poll(std::chrono::steady_clock::time_point now, std::uint32_t body_count);

 private:
  struct Introspection;
  std::unique_ptr<Introspection> introspection_;
  Writer<Health> writer_;
  std::chrono::steady_clock::time_point started_;
  std::chrono::steady_clock::time_point last_publish_;
};

}  // namespace afhub
