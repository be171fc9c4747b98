// The hub's catalog: discovers every process's body directory, merges them,
// measures each body's publish rate, and publishes the result.
// Rates are what each state's writer tells of itself in its slot (its count of updates
// and the stamp of the last, see slot_activity()), read once a second: the hub reads
// no state and holds no entry, so no writer pays for it, however many bodies.
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <optional>
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
  // A body's (or device's) rate, from two looks at its writer's slot.
  struct Rate {
    ChannelKind kind = ChannelKind::kBody;
    std::optional<SlotActivity> last;  // at the last look
    std::chrono::steady_clock::time_point looked;
    double hz = 0.0;
  };
  bool refresh_directories();
  // Rebuilds the body list when a directory changed; true if it did.
  bool merge(bool directories_changed);
  // Looks at each body's slot once per kSamplePeriod, its rate from the last look.
  void sample_rates(std::chrono::steady_clock::time_point now);
  void publish();
  // Says `message` on stderr, unless it was said already.
  void tell_once(const std::string& message);

  ChannelDiscovery discovery_;
  std::map<std::string, std::unique_ptr<CopyingReader>> directories_;  // by owner instance
  std::map<std::string, Rate> rates_;                                  // by body channel
  std::vector<BodyEntry> bodies_;
  std::set<std::string> told_;
  RawWriter writer_;
  std::chrono::steady_clock::time_point last_publish_;
};

}  // namespace afhub
