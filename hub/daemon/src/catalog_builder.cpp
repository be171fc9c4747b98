// The hub's catalog (see catalog_builder.hpp).
#include "catalog_builder.hpp"

#include <cstdio>

#include "afhub/hub/bodies.hpp"

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
  for (auto& [instance, reader] : directories_) {
    reader->latest();
    any_update = any_update || reader->updated();
  }
  if (!any_update) return false;
  // What the live directories offer, in their order; a body two processes offer
  // goes to the one the catalog already lists, else to the first.
  std::map<std::string, std::uint32_t> admitted_owner;
  for (const auto& body : bodies_)
    admitted_owner[std::string(name_of(body.channel))] = body.owner_pid;
  std::vector<BodyInfo> offered;
  std::map<std::string, std::size_t> offered_at;
  for (auto& [instance, reader] : directories_) {
    const auto* list = static_cast<const BodyList*>(reader->latest());
    if (!list) continue;
    for (std::uint32_t i = 0; i < list->body_count; ++i) {
      const BodyInfo& body = list->bodies[i];
      std::string channel(name_of(body.channel));
      const auto [at, added] = offered_at.emplace(channel, offered.size());
      if (added) {
        offered.push_back(body);
        continue;
      }
      std::fprintf(stderr, "afhub hub: body %s is claimed by two processes; keeping the first\n",
                   channel.c_str());
      const auto admitted = admitted_owner.find(channel);
      if (admitted != admitted_owner.end() && admitted->second == body.owner_pid)
        offered[at->second] = body;
    }
  }
  // First come, first served: bodies the catalog lists keep their place, new ones
  // join while there is room. Their owner sees the refused ones missing and says so.
  std::vector<BodyInfo> merged;
  std::vector<bool> taken(offered.size(), false);
  for (const auto& body : bodies_) {
    const auto at = offered_at.find(std::string(name_of(body.channel)));
    if (at == offered_at.end() || taken[at->second]) continue;
    merged.push_back(offered[at->second]);
    taken[at->second] = true;
  }
  for (std::size_t k = 0; k < offered.size(); ++k) {
    if (taken[k]) continue;
    if (merged.size() == kMaxBodies) {
      std::fprintf(stderr, "afhub hub: the catalog is full (%zu bodies); %s of %s is refused\n",
                   kMaxBodies, std::string(name_of(offered[k].channel)).c_str(),
                   std::string(name_of(offered[k].owner)).c_str());
      continue;
    }
    merged.push_back(offered[k]);
  }
  bodies_ = std::move(merged);
  // Rate probes follow the body set.
  std::map<std::string, RateProbe> probes;
  for (const auto& body : bodies_) {
    std::string channel(name_of(body.channel));
    auto old = rates_.find(channel);
    if (old != rates_.end()) {
      probes[channel] = std::move(old->second);
    } else {
      probes[channel].reader =
          std::make_unique<LatestReader<BodyState>>(body_state_channel(channel));
    }
  }
  rates_ = std::move(probes);
  return true;
}

void CatalogBuilder::take_rate_samples() {
  for (auto& [channel, probe] : rates_) {
    if (!probe.sampling) continue;
    const BodyState* state = probe.reader->latest();
    if (!probe.reader->updated()) continue;
    const std::uint64_t sequence = state->header.sequence;
    const std::int64_t stamp_ns = state->header.publish_stamp_ns;
    if (probe.last_sequence != 0 && sequence >= probe.last_sequence &&
        stamp_ns > probe.last_stamp_ns)
      probe.rate_hz = static_cast<double>(sequence - probe.last_sequence) * 1e9 /
                      static_cast<double>(stamp_ns - probe.last_stamp_ns);
    probe.last_sequence = sequence;
    probe.last_stamp_ns = stamp_ns;
    probe.sampling = false;
    probe.reader->raw().unsubscribe();
  }
}

void CatalogBuilder::start_rate_samples() {
  for (auto& [channel, probe] : rates_) {
    if (probe.sampling) {
      probe.rate_hz = 0.0;  // nothing published for a whole round
      continue;
    }
    probe.sampling = true;
    probe.reader->raw().subscribe();
  }
}

void CatalogBuilder::publish() {
  auto* list = static_cast<BodyList*>(writer_.loan(body_list_bytes(bodies_.size())));
  if (!list) {
    std::fprintf(stderr, "afhub hub: shared memory exhausted, catalog not published\n");
    return;
  }
  list->header = PayloadHeader{};
  list->body_count = static_cast<std::uint32_t>(bodies_.size());
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    list->bodies[i] = bodies_[i];
    list->bodies[i].publish_rate_hz = rates_[std::string(name_of(bodies_[i].channel))].rate_hz;
  }
  writer_.publish(list);
}

}  // namespace afhub
