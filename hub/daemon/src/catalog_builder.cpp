// The hub's catalog (see catalog_builder.hpp).
#include "catalog_builder.hpp"

#include <cstdio>

#include "afhub/hub/bodies.hpp"
#include "afhub/shm_layout/error.hpp"
#include "catalog_merge.hpp"

namespace afhub {
namespace {
constexpr auto kRepublishPeriod = std::chrono::seconds(1);
constexpr auto kSamplePeriod = std::chrono::seconds(1);
}  // namespace

CatalogBuilder::CatalogBuilder()
    : writer_({std::string(kService), std::string(kHubInstance), std::string(kCatalogEvent)},
              PayloadKind::kCatalog) {
  publish();  // an empty catalog at once: tools can tell a hub from a plain RouDi
}

CatalogBuilder::~CatalogBuilder() = default;

void CatalogBuilder::poll(std::chrono::steady_clock::time_point now) {
  const bool changed = merge(refresh_directories());
  take_rate_samples(now);
  start_rate_samples(now);
  const bool due = now - last_publish_ >= kRepublishPeriod;
  if (due) last_publish_ = now;
  if (changed || due) publish();
}

bool CatalogBuilder::refresh_directories() {
  return discovery_.follow(kDirectoryEvent, directories_, [this](const std::string& instance) {
    try {
      return std::make_unique<CopyingReader>(
          ChannelId{std::string(kService), instance, std::string(kDirectoryEvent)},
          PayloadKind::kBodyDirectory);
    } catch (const Error& error) {  // no subscriber port left: tried again on the next poll
      tell_once("the bodies of " + instance + " are not listed yet: " + error.what());
      return std::unique_ptr<CopyingReader>();
    }
  });
}

bool CatalogBuilder::merge(bool directories_changed) {
  bool any_update = directories_changed;
  std::vector<OfferedDirectory> offered;
  for (auto& [instance, reader] : directories_) {
    // A checked copy: every count fits, whatever its writer does meanwhile.
    offered.push_back({instance, static_cast<const BodyList*>(reader->latest())});
    any_update = any_update || reader->updated();
  }
  if (!any_update) return false;
  std::vector<std::string> messages;
  bodies_ = merge_directories(bodies_, offered, messages);
  for (const std::string& message : messages) tell_once(message);
  // Rate probes follow the body set; each opens its reader when it samples.
  std::map<std::string, RateProbe> probes;
  for (const BodyEntry& body : bodies_) {
    std::string channel(name_of(body.info.channel));
    auto old = rates_.find(channel);
    RateProbe& probe = probes[channel];
    if (old != rates_.end()) probe = std::move(old->second);
    probe.kind = body.info.kind;
  }
  rates_ = std::move(probes);
  return true;
}

void CatalogBuilder::tell_once(const std::string& message) {
  // A faulty writer may publish new faults forever: the memory of what was said is bounded.
  if (told_.size() > 1000) told_.clear();
  if (told_.insert(message).second) std::fprintf(stderr, "afhub hub: %s\n", message.c_str());
}

void CatalogBuilder::take_rate_samples(std::chrono::steady_clock::time_point now) {
  for (auto& [channel, probe] : rates_) {
    if (!probe.sampling) continue;
    const auto* header = static_cast<const PayloadHeader*>(probe.reader->latest());
    if (!probe.reader->updated()) {
      if (now - probe.started >= kSamplePeriod) {
        probe.rate_hz = 0.0;  // nothing published for a whole period
        probe.last_sequence = 0;
        end_sample(probe);
      }
      continue;
    }
    const std::uint64_t sequence = header->sequence;
    const std::int64_t stamp_ns = header->publish_stamp_ns;
    if (probe.last_sequence != 0 && sequence >= probe.last_sequence &&
        stamp_ns > probe.last_stamp_ns)
      probe.rate_hz = static_cast<double>(sequence - probe.last_sequence) * 1e9 /
                      static_cast<double>(stamp_ns - probe.last_stamp_ns);
    probe.last_sequence = sequence;
    probe.last_stamp_ns = stamp_ns;
    end_sample(probe);
  }
}

void CatalogBuilder::end_sample(RateProbe& probe) {
  probe.sampling = false;
  if (rates_.size() <= kMaxRateProbes)
    probe.reader->unsubscribe();
  else
    probe.reader.reset();  // its port, for the next body round
}

void CatalogBuilder::start_rate_samples(std::chrono::steady_clock::time_point now) {
  const bool few = rates_.size() <= kMaxRateProbes;
  std::size_t open = 0;
  for (auto& [channel, probe] : rates_) {
    if (!few && !probe.sampling) probe.reader.reset();  // kept from when there were few
    open += probe.reader ? 1 : 0;
  }
  if (rates_.empty()) return;
  // Once round the bodies, from where the last call stopped.
  auto it = rates_.lower_bound(next_probe_);
  for (std::size_t visited = 0; visited < rates_.size(); ++visited, ++it) {
    if (it == rates_.end()) it = rates_.begin();
    auto& [channel, probe] = *it;
    if (probe.sampling || (probe.started != std::chrono::steady_clock::time_point{} &&
                           now - probe.started < kSamplePeriod))
      continue;
    if (probe.reader) {
      probe.reader->subscribe();
    } else {
      if (open == kMaxRateProbes) {
        next_probe_ = channel;
        return;
      }
      try {
        probe.reader = std::make_unique<RawLatestReader>(body_state_channel(channel),
                                                         probe.kind == ChannelKind::kDevice
                                                             ? PayloadKind::kDeviceState
                                                             : PayloadKind::kBodyState);
      } catch (const std::exception& error) {  // no subscriber port left, or a bad name
        tell_once("no publish rate for " + channel + ": " + error.what());
        next_probe_ = channel;
        return;
      }
      ++open;
    }
    probe.sampling = true;
    probe.started = now;
  }
}

void CatalogBuilder::publish() {
  BodyList* list = loan_body_list(writer_, bodies_);
  if (!list) {
    tell_once("the catalog of " + std::to_string(bodies_.size()) +
              " bodies is not published: shared memory is exhausted, or its joint names "
              "exceed a catalog's; give the hub a larger pool (--pool BYTES:COUNT)");
    return;
  }
  for (std::size_t i = 0; i < bodies_.size(); ++i)
    list->bodies[i].publish_rate_hz = rates_[std::string(name_of(bodies_[i].info.channel))].rate_hz;
  writer_.publish(list);
}

}  // namespace afhub
