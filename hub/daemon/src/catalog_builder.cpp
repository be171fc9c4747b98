// The hub's catalog (see catalog_builder.hpp).
#include "catalog_builder.hpp"

#include <cstdio>

#include "afhub/hub/bodies.hpp"
#include "catalog_merge.hpp"

namespace afhub {
namespace {
constexpr auto kRepublishPeriod = std::chrono::seconds(1);
}

CatalogBuilder::CatalogBuilder()
    : writer_({std::string(kService), std::string(kHubInstance), std::string(kCatalogEvent)},
              PayloadKind::kCatalog) {
  publish();  // an empty catalog at once: tools can tell a hub from a plain RouDi
}

CatalogBuilder::~CatalogBuilder() = default;

void CatalogBuilder::poll(std::chrono::steady_clock::time_point now) {
  const bool changed = merge(refresh_directories());
  take_rate_samples();
  const bool due = now - last_publish_ >= kRepublishPeriod;
  if (due) {
    start_rate_samples();
    last_publish_ = now;
  }
  if (changed || due) publish();
}

bool CatalogBuilder::refresh_directories() {
  return discovery_.follow(kDirectoryEvent, directories_, [](const std::string& instance) {
    return std::make_unique<RawLatestReader>(
        ChannelId{std::string(kService), instance, std::string(kDirectoryEvent)},
        PayloadKind::kBodyDirectory);
  });
}

bool CatalogBuilder::merge(bool directories_changed) {
  bool any_update = directories_changed;
  std::vector<OfferedDirectory> offered;
  for (auto& [instance, reader] : directories_) {
    // Checked by the reader (check_payload): every count fits its chunk.
    offered.push_back({instance, static_cast<const BodyList*>(reader->latest())});
    any_update = any_update || reader->updated();
  }
  if (!any_update) return false;
  std::vector<std::string> messages;
  bodies_ = merge_directories(bodies_, offered, messages);
  for (const std::string& message : messages) tell_once(message);
  // Rate probes follow the body set. A body whose probe cannot open is dropped,
  // said once: one bad entry never stops the hub.
  std::map<std::string, RateProbe> probes;
  std::erase_if(bodies_, [&](const BodyEntry& body) {
    std::string channel(name_of(body.info.channel));
    auto old = rates_.find(channel);
    if (old != rates_.end()) {
      probes[channel] = std::move(old->second);
      return false;
    }
    try {
      probes[channel].reader = std::make_unique<RawLatestReader>(
          body_state_channel(channel), body.info.kind == ChannelKind::kDevice
                                           ? PayloadKind::kDeviceState
                                           : PayloadKind::kBodyState);
      return false;
    } catch (const std::exception& error) {
      probes.erase(channel);
      tell_once("body " + channel + " of " + std::string(name_of(body.info.owner)) +
                " is not listed: " + error.what());
      return true;
    }
  });
  rates_ = std::move(probes);
  return true;
}

void CatalogBuilder::tell_once(const std::string& message) {
  // A faulty writer may publish new faults forever: the memory of what was said is bounded.
  if (told_.size() > 1000) told_.clear();
  if (told_.insert(message).second) std::fprintf(stderr, "afhub hub: %s\n", message.c_str());
}

void CatalogBuilder::take_rate_samples() {
  for (auto& [channel, probe] : rates_) {
    if (!probe.sampling) continue;
    const auto* header = static_cast<const PayloadHeader*>(probe.reader->latest());
    if (!probe.reader->updated()) continue;
    const std::uint64_t sequence = header->sequence;
    const std::int64_t stamp_ns = header->publish_stamp_ns;
    if (probe.last_sequence != 0 && sequence >= probe.last_sequence &&
        stamp_ns > probe.last_stamp_ns)
      probe.rate_hz = static_cast<double>(sequence - probe.last_sequence) * 1e9 /
                      static_cast<double>(stamp_ns - probe.last_stamp_ns);
    probe.last_sequence = sequence;
    probe.last_stamp_ns = stamp_ns;
    probe.sampling = false;
    probe.reader->unsubscribe();
  }
}

void CatalogBuilder::start_rate_samples() {
  for (auto& [channel, probe] : rates_) {
    if (probe.sampling) {
      probe.rate_hz = 0.0;  // nothing published for a whole round
      continue;
    }
    probe.sampling = true;
    probe.reader->subscribe();
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
