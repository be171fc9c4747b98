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
  sample_rates(now);
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
  // Rates follow the body set.
  std::map<std::string, Rate> rates;
  for (const BodyEntry& body : bodies_) {
    std::string channel(name_of(body.info.channel));
    auto old = rates_.find(channel);
    Rate& rate = rates[channel];
    if (old != rates_.end()) rate = old->second;
    rate.kind = body.info.kind;
  }
  rates_ = std::move(rates);
  return true;
}

void CatalogBuilder::tell_once(const std::string& message) {
  // A faulty writer may publish new faults forever: the memory of what was said is bounded.
  if (told_.size() > 1000) told_.clear();
  if (told_.insert(message).second) std::fprintf(stderr, "afhub hub: %s\n", message.c_str());
}

void CatalogBuilder::sample_rates(std::chrono::steady_clock::time_point now) {
  release_gone_slot_writers();  // their chunks back to the pools, even with no body left
  for (auto& [channel, rate] : rates_) {
    if (now - rate.looked < kSamplePeriod) continue;
    rate.looked = now;
    std::optional<SlotActivity> activity;
    try {
      activity = slot_activity(body_state_channel(channel), rate.kind == ChannelKind::kDevice
                                                                ? PayloadKind::kDeviceState
                                                                : PayloadKind::kBodyState);
    } catch (const std::exception& error) {  // no subscriber port for the directory, a bad name
      tell_once("no publish rate for " + channel + ": " + error.what());
    }
    const std::optional<SlotActivity> last = rate.last;
    rate.last = activity;
    if (!activity || !last || activity->writer != last->writer) {
      rate.hz = 0.0;  // no writer, or a new one: a rate from the next look
      continue;
    }
    // Unsigned: a count that wrapped still gives the updates between the two looks.
    const std::uint32_t updates = (activity->updates - last->updates) & 0x7fffffffU;
    const std::int64_t span_ns = activity->last_stamp_ns - last->last_stamp_ns;
    rate.hz = span_ns > 0 ? static_cast<double>(updates) * 1e9 / static_cast<double>(span_ns)
                          : 0.0;  // nothing published for a whole period
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
    list->bodies[i].publish_rate_hz = rates_[std::string(name_of(bodies_[i].info.channel))].hz;
  writer_.publish(list);
}

}  // namespace afhub
