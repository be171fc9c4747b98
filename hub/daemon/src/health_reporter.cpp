// The hub's health channel (see health_reporter.hpp).
#include "health_reporter.hpp"

#include <algorithm>
#include <cstring>
#include <optional>

#include "iceoryx_posh/popo/subscriber.hpp"
#include "iceoryx_posh/roudi/introspection_types.hpp"

namespace afhub {
namespace {

constexpr auto kPublishPeriod = std::chrono::seconds(1);
constexpr auto kSubscriberPeriod = std::chrono::milliseconds(100);

}  // namespace

struct HealthReporter::Introspection {
  // Keeps the newest sample of an introspection topic; `fresh` while it is unpublished.
  template <class Topic>
  struct LatestTopic {
    explicit LatestTopic(const iox::capro::ServiceDescription& service)
        : subscriber(service, latest_only()) {}
    static iox::popo::SubscriberOptions latest_only() {
      iox::popo::SubscriberOptions options;
      options.queueCapacity = 1;
      options.historyRequest = 1;
      return options;
    }
    const Topic* latest() {
      for (;;) {
        auto taken = subscriber.take();
        if (taken.has_error()) break;
        held.emplace(std::move(taken.value()));
        fresh = true;
      }
      return held ? held->get() : nullptr;
    }
    iox::popo::Subscriber<Topic> subscriber;
    std::optional<iox::popo::Sample<const Topic>> held;
    bool fresh = false;
  };

  LatestTopic<iox::roudi::ProcessIntrospectionFieldTopic> processes{
      iox::roudi::IntrospectionProcessService};
  LatestTopic<iox::roudi::MemPoolIntrospectionInfoContainer> mempools{
      iox::roudi::IntrospectionMempoolService};
};

HealthReporter::HealthReporter()
    : introspection_(std::make_unique<Introspection>()),
      writer_({std::string(kService), std::string(kHubInstance), std::string(kHealthEvent)}),
      started_(std::chrono::steady_clock::now()) {}

HealthReporter::~HealthReporter() = default;

void HealthReporter::poll(std::chrono::steady_clock::time_point now, std::uint32_t body_count,
                          FreePorts free_ports) {
  const auto* processes = introspection_->processes.latest();
  const auto* mempools = introspection_->mempools.latest();
  // At once on start (processes and mempools follow with RouDi's introspection),
  // then once a second.
  // Also at once when the bodies or the free publisher ports change (writers check
  // them), and within kSubscriberPeriod when the free subscriber ports do (readers
  // check them; the rate probes of many bodies come and go all the time), and as
  // often when RouDi measured the pools anew (new processes check their chunks).
  const bool changed =
      body_count != last_body_count_ || free_ports.publishers != last_free_ports_.publishers;
  const bool readers_changed = free_ports.subscribers != last_free_ports_.subscribers;
  const bool soon = (readers_changed || introspection_->mempools.fresh) &&
                    now - last_publish_ >= kSubscriberPeriod;
  if (last_publish_ != std::chrono::steady_clock::time_point{} && !changed && !soon &&
      now - last_publish_ < kPublishPeriod)
    return;
  Health* health = writer_.loan();
  if (!health) return;
  last_publish_ = now;
  last_body_count_ = body_count;
  last_free_ports_ = free_ports;
  health->hub_uptime_s = std::chrono::duration<double>(now - started_).count();
  health->body_count = body_count;
  health->free_publisher_ports = free_ports.publishers;
  health->free_subscriber_ports = free_ports.subscribers;
  if (processes) {
    for (const auto& process : processes->m_processList) {
      if (health->process_count == kMaxHealthProcesses) break;
      ProcessEntry& entry = health->processes[health->process_count++];
      entry.pid = process.m_pid;
      std::strncpy(entry.name.data(), process.m_name.c_str(), entry.name.size() - 1);
    }
  }
  if (mempools) {
    introspection_->mempools.fresh = false;
    for (const auto& segment : *mempools) {
      for (const auto& pool : segment.m_mempoolInfo) {
        if (health->mempool_count == kMaxMempools) break;
        MempoolUsage& usage = health->mempools[health->mempool_count++];
        usage.segment_id = segment.m_id;
        usage.chunk_payload_bytes = pool.m_chunkPayloadSize;
        usage.chunk_count = pool.m_numChunks;
        usage.used_chunks = pool.m_usedChunks;
        usage.min_free_chunks = pool.m_minFreeChunks;
      }
    }
  }
  writer_.publish(health);
}

std::vector<std::pair<std::string, pid_t>> HealthReporter::registered_processes() {
  std::vector<std::pair<std::string, pid_t>> registered;
  if (const auto* processes = introspection_->processes.latest())
    for (const auto& process : processes->m_processList)
      registered.emplace_back(process.m_name.c_str(), static_cast<pid_t>(process.m_pid));
  return registered;
}

}  // namespace afhub
