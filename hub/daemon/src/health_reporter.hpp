// The hub's health channel: live processes and mempool usage, relayed from
// RouDi's introspection, plus uptime and body count: once a second, and within 100 ms
// of a change (see poll).
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "afhub/hub/channel.hpp"
#include "afhub/hub/hub_health.hpp"
#include "afhub/shm_layout/health.hpp"

namespace afhub {

class HealthReporter {
 public:
  HealthReporter();
  ~HealthReporter();
  void poll(std::chrono::steady_clock::time_point now, std::uint32_t body_count,
            FreePorts free_ports);
  // The processes RouDi has registered, as its introspection last said: (name, pid).
  std::vector<std::pair<std::string, pid_t>> registered_processes();

 private:
  struct Introspection;
  std::unique_ptr<Introspection> introspection_;
  Writer<Health> writer_;
  std::chrono::steady_clock::time_point started_;
  std::chrono::steady_clock::time_point last_publish_;
  std::uint32_t last_body_count_ = 0;
  FreePorts last_free_ports_;
};

}  // namespace afhub
