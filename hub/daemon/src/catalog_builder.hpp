// The hub's catalog: discovers every process's body directory, merges them,
// measures each body's publish rate, and publishes the result.
// Rates come from one state sample per body a second, (sequence, publish stamp)
// against the last: the hub subscribes until that sample arrives and then steps
// aside, so it is not a reader the physics pays for on every step.
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/channel.hpp"
#include "afhub/hub/channel_discovery.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/catalog.hpp"

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
    std::unique_ptr<RawLatestReader>
        reader;  // a body's or a device's state; subscribed while sampling
    bool sampling = true;
    std::uint64_t last_sequence = 0;
    std::int64_t last_stamp_ns = 0;
    double rate_hz = 0.0;
  };
  bool refresh_directories();
  // Rebuilds the body list when a directory changed; true if it did.
  bool merge(bool directories_changed);
  // Takes the sample each sampling probe waits for, and steps aside.
  void take_rate_samples();
  // Starts the next round of samples; a probe still waiting after a whole round
  // has a silent publisher.
  void start_rate_samples();
  void publish();
  // Says `message` on stderr, unless it was said already.
  void tell_once(const std::string& message);

  ChannelDiscovery discovery_;
  std::map<std::string, std::unique_ptr<RawLatestReader>> directories_;  // by owner instance
  std::map<std::string, RateProbe> rates_;                               // by body channel
  std::vector<BodyEntry> bodies_;
  std::set<std::string> told_;
  RawWriter writer_;
  std::chrono::steady_clock::time_point last_publish_;
};

}  // namespace afhub
