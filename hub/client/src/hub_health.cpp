// The iceoryx ports left (see hub_health.hpp).
#include "afhub/hub/hub_health.hpp"

#include <algorithm>
#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <thread>

#include "afhub/hub/channel.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/health.hpp"
#include "iceoryx_posh/iceoryx_posh_types.hpp"

namespace afhub {
namespace {

std::atomic<std::int64_t> g_publishers_left{-1};  // -1: not counted
std::atomic<std::int64_t> g_subscribers_left{-1};
std::atomic<std::int64_t> g_last_taken_ns{0};  // this process's last port taken
constexpr std::int64_t kRecountBelow = 32;
// Set while this thread reads the Health to count afresh: that reader uses the reserve.
thread_local bool t_recounting = false;

std::string publishers_message(std::size_t count, std::int64_t left, const std::string& what) {
  return what + " needs " + std::to_string(count) + " iceoryx publisher port" +
         (count == 1 ? "" : "s") + " and the hub has " + std::to_string(left) + " left of " +
         std::to_string(iox::MAX_PUBLISHERS) +
         " (one per block of slots a process writes, each holding many bodies' states or "
         "commands, and one per queue). Stop another afhub process";
}

std::string subscribers_message(std::size_t count, std::int64_t left, const std::string& what) {
  return what + " needs " + std::to_string(count) + " iceoryx subscriber port" +
         (count == 1 ? "" : "s") + " and the hub has " + std::to_string(left) + " left of " +
         std::to_string(iox::MAX_SUBSCRIBERS) + " (" + std::to_string(kReservedSubscriberPorts) +
         " of them kept for reading the hub's health; each process takes one per kind of "
         "slot it reads (states, commands) and one per queue). Stop another afhub process or "
         "bridge";
}

// A process is refused while it would leave fewer free chunks than this in a pool:
// those running take more as readers come and go.
constexpr std::uint32_t kMinSpareChunks = 4;
constexpr std::uint32_t kSpareChunksPerPool = 16;  // 1/16 of a pool, when more

// The hub's payload pools, as the last Health read here said (empty before, or while
// RouDi had not yet measured them). RouDi's own introspection pools come first.
std::mutex g_pools_mutex;
std::vector<MempoolUsage> g_pools;

void remember_pools(const Health& health) {
  const std::uint32_t count = std::min<std::uint32_t>(health.mempool_count, kMaxMempools);
  const std::lock_guard lock(g_pools_mutex);
  g_pools.clear();
  for (std::uint32_t i = 0; i < count; ++i)
    if (health.mempools[i].segment_id != health.mempools[0].segment_id)
      g_pools.push_back(health.mempools[i]);
}

// The ports a Health read through `health` (made at `opened_ns`) says are free, less the
// reader's own port when that Health was published before it: a port given back is
// free again only once RouDi gets to it.
std::optional<FreePorts> read_free_ports(LatestReader<Health>& health, std::int64_t opened_ns,
                                         std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!health.latest() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  const Health* latest = health.latest();
  if (!latest) return std::nullopt;
  remember_pools(*latest);
  const std::uint32_t own = latest->header.publish_stamp_ns < opened_ns ? 1 : 0;
  return FreePorts{latest->free_publisher_ports,
                   latest->free_subscriber_ports > own ? latest->free_subscriber_ports - own : 0};
}

std::unique_ptr<LatestReader<Health>> open_health_reader() {
  struct Recounting {
    Recounting() { t_recounting = true; }
    ~Recounting() { t_recounting = false; }
  } recounting;
  return std::make_unique<LatestReader<Health>>(
      ChannelId{std::string(kService), std::string(kHubInstance), std::string(kHealthEvent)});
}

// Near the end, counted afresh through a reader kept from then on: a reader made for
// each count would take a port each time until RouDi gives it back.
void recount() {
  static std::mutex mutex;
  static std::unique_ptr<LatestReader<Health>> health;
  static std::int64_t opened_ns = 0;
  const std::lock_guard lock(mutex);
  if (!health) {
    opened_ns = monotonic_ns();
    health = open_health_reader();
  }
  std::optional<FreePorts> free =
      read_free_ports(*health, opened_ns, std::chrono::milliseconds(500));
  // A Health older than this process's last port does not count it yet.
  if (free && health->latest()->header.publish_stamp_ns < g_last_taken_ns) {
    if (g_publishers_left >= 0)
      free->publishers =
          std::min(free->publishers, static_cast<std::uint32_t>(g_publishers_left.load()));
    if (g_subscribers_left >= 0)
      free->subscribers =
          std::min(free->subscribers, static_cast<std::uint32_t>(g_subscribers_left.load()));
  }
  count_ports_from(free);
}

}  // namespace

std::optional<FreePorts> free_ports(std::chrono::milliseconds timeout) {
  const std::int64_t opened_ns = monotonic_ns();
  const std::unique_ptr<LatestReader<Health>> health = open_health_reader();
  return read_free_ports(*health, opened_ns, timeout);
}

std::optional<std::uint32_t> free_publisher_ports(std::chrono::milliseconds timeout) {
  const std::optional<FreePorts> free = free_ports(timeout);
  if (!free) return std::nullopt;
  return free->publishers;
}

std::vector<ChunkNeed> written_as_slots(const std::vector<SlotWritten>& slots) {
  std::map<std::pair<PayloadKind, std::uint32_t>, std::size_t> entries;
  for (const SlotWritten& slot : slots)
    ++entries[{slot.kind, slot_payload_capacity(static_cast<std::uint32_t>(slot.payload_bytes))}];
  std::vector<ChunkNeed> needs;
  for (const auto& [size, count] : entries) {
    const std::uint32_t capacity = size.second;
    for (std::size_t nth = 0, held = 0; held < count; held += slot_block_entries(nth++, capacity))
      needs.push_back({static_cast<std::uint32_t>(slot_block_loan_bytes(nth, capacity)), 1});
  }
  return needs;
}

void require_chunks(const std::vector<ChunkNeed>& needs, const std::string& what) {
  // Read afresh: a process checks long after it connected (a model takes seconds to
  // load), and others take chunks meanwhile.
  free_ports(std::chrono::milliseconds(500));
  const std::lock_guard lock(g_pools_mutex);
  std::vector<std::uint32_t> needed(g_pools.size(), 0);  // pools sorted by size, as iceoryx's
  for (const ChunkNeed& need : needs)
    for (std::size_t i = 0; i < g_pools.size(); ++i)
      if (g_pools[i].chunk_payload_bytes >= need.bytes) {
        needed[i] += need.count;
        break;
      }
  for (std::size_t i = 0; i < g_pools.size(); ++i) {
    const MempoolUsage& pool = g_pools[i];
    const std::uint32_t free = pool.chunk_count - std::min(pool.used_chunks, pool.chunk_count);
    const std::uint32_t spare = std::max(kMinSpareChunks, pool.chunk_count / kSpareChunksPerPool);
    if (needed[i] == 0 || free >= needed[i] + spare) continue;
    const std::string bytes = std::to_string(pool.chunk_payload_bytes);
    throw Error(what + " needs " + std::to_string(needed[i]) + " chunks of the hub's pool of " +
                std::to_string(pool.chunk_count) + " chunks of " + bytes + " bytes, and " +
                std::to_string(free) +
                " are free: a new process is refused while it would leave "
                "fewer than " +
                std::to_string(spare) +
                ", so that those running keep publishing. Stop another process (`afhub status` "
                "shows them and the pools), or give the hub more (`afhub hub --pool " +
                bytes + ":COUNT`)");
  }
}

void count_ports_from(std::optional<FreePorts> free) {
  count_publisher_ports_from(free ? std::optional(free->publishers) : std::nullopt);
  count_subscriber_ports_from(free ? std::optional(free->subscribers) : std::nullopt);
}

void count_publisher_ports_from(std::optional<std::uint32_t> free) {
  g_publishers_left = free ? static_cast<std::int64_t>(*free) : -1;
}

void count_subscriber_ports_from(std::optional<std::uint32_t> free) {
  g_subscribers_left = free ? static_cast<std::int64_t>(*free) : -1;
}

void require_publisher_ports(std::size_t count, const std::string& what) {
  const auto wanted = static_cast<std::int64_t>(count);
  // Near the end, counted afresh: other processes take and give back ports too.
  if (g_publishers_left >= 0 && g_publishers_left < wanted + kRecountBelow) recount();
  const std::int64_t left = g_publishers_left;
  if (left >= 0 && left < wanted) throw Error(publishers_message(count, left, what));
}

void require_subscriber_ports(std::size_t count, const std::string& what) {
  if (t_recounting) return;
  const auto wanted = static_cast<std::int64_t>(count) + kReservedSubscriberPorts;
  if (g_subscribers_left >= 0 && g_subscribers_left < wanted + kRecountBelow) recount();
  const std::int64_t left = g_subscribers_left;
  if (left >= 0 && left < wanted) throw Error(subscribers_message(count, left, what));
}

void took_publisher_port() noexcept {
  g_last_taken_ns = monotonic_ns();
  if (g_publishers_left > 0) --g_publishers_left;
}

void gave_back_publisher_port() noexcept {
  if (g_publishers_left >= 0) ++g_publishers_left;
}

void took_subscriber_port() noexcept {
  g_last_taken_ns = monotonic_ns();
  if (g_subscribers_left > 0) --g_subscribers_left;
}

void gave_back_subscriber_port() noexcept {
  if (g_subscribers_left >= 0) ++g_subscribers_left;
}

}  // namespace afhub
