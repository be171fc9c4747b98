// The hub's catalog: discovers every process's body directory, merges them,
// measures each body's publish rate, and publishes the result.
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "afhub/hub/channel.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/catalog.hpp"

namespace iox::runtime {
class ServiceDiscovery;
}

namespace afhub {

class CatalogBuilder {
 public:
  CatalogBuilder();
  ~CatalogBuilder();
  // Follows directories appearing and vanishing, and republishes the catalog on
  // any change and at least once a second with fresh rates.
  void poll(std::chrono::steady_clock::time_point now);
  std::uint32_t body_count() const { return static_cast<std::uint32_t>(bodies_.size()); }

 private:
  struct RateProbe {
    std::unique_ptr<LatestReader<BodyState>> reader;
    std::uint64_t last_sequence = 0;
    std::chrono::steady_clock::time_point last_time;
    double rate_hz = 0.0;
  };
  bool refresh_directories();
  // Rebuilds the body list when a directory changed; true if it did.
  bool merge(bool directories_changed);
  void measure_rates(std::chrono::steady_clock::time_point now);
  void publish();

  std::unique_ptr<iox::runtime::ServiceDiscovery> discovery_;
  std::map<std::string, std::unique_ptr<RawLatestReader>> directories_;  // by owner instance
  std::map<std::string, RateProbe> rates_;                               // by body channel
  std::vector<BodyInfo> bodies_;
  RawWriter writer_;
  std::chrono::steady_clock::time_point last_publish_;
};

}  // namespace afhub
