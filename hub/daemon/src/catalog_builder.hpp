// The hub's catalog: discovers every process's body directory, merges them,
// measures each body's publish rate, and publishes the result.
// Rates come from one state sample per body a second, (sequence, publish stamp)
// against the last: the hub subscribes until that sample arrives and then steps
// aside, so it is not a reader the physics pays for on every step. A probe is an
// iceoryx subscriber port, of which there are 1024 for every reader on the machine:
// at most kMaxRateProbes are open at once. With more bodies than that, the probes go
// round them, each opened for its sample and closed.
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
#include "afhub/hub/copying_reader.hpp"
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
  static constexpr std::size_t kMaxRateProbes = 32;
  struct RateProbe {
    // A body's or a device's state: open while sampling; with few bodies, kept
    // (unsubscribed) in between.
    std::unique_ptr<RawLatestReader> reader;
    bool sampling = false;
    std::chrono::steady_clock::time_point started;  // the last sample's
    std::uint64_t last_sequence = 0;
    std::int64_t last_stamp_ns = 0;
    double rate_hz = 0.0;
    ChannelKind kind = ChannelKind::kBody;
  };
  bool refresh_directories();
  // Rebuilds the body list when a directory changed; true if it did.
  bool merge(bool directories_changed);
  // Takes the sample each sampling probe waits for, and steps aside; a probe still
  // waiting after kSamplePeriod has a silent publisher.
  void take_rate_samples(std::chrono::steady_clock::time_point now);
  // Starts a sample of each body whose last one began kSamplePeriod ago, going round
  // the bodies while probes are free.
  void start_rate_samples(std::chrono::steady_clock::time_point now);
  void end_sample(RateProbe& probe);
  void publish();
  // Says `message` on stderr, unless it was said already.
  void tell_once(const std::string& message);

  ChannelDiscovery discovery_;
  std::map<std::string, std::unique_ptr<CopyingReader>> directories_;  // by owner instance
  std::map<std::string, RateProbe> rates_;                             // by body channel
  std::string next_probe_;  // where start_rate_samples() goes on round the bodies
  std::vector<BodyEntry> bodies_;
  std::set<std::string> told_;
  RawWriter writer_;
  std::chrono::steady_clock::time_point last_publish_;
};

}  // namespace afhub
