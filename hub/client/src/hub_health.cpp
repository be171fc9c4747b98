// The publisher ports left (see hub_health.hpp).
#include "afhub/hub/hub_health.hpp"

#include <atomic>
#include <thread>

#include "afhub/hub/channel.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/health.hpp"

namespace afhub {
namespace {

std::atomic<std::int64_t> g_ports_left{-1};  // -1: not counted
constexpr std::int64_t kRecountBelow = 32;

std::string ports_message(std::size_t count, std::int64_t left, const std::string& what) {
  return what + " needs " + std::to_string(count) + " iceoryx publisher port" +
         (count == 1 ? "" : "s") + " and the hub has " + std::to_string(left) +
         " left of 512 (one per body state, per command writer, per loop's stats). Stop "
         "another afhub process, or simulate fewer bodies";
}

}  // namespace

std::optional<std::uint32_t> free_publisher_ports(std::chrono::milliseconds timeout) {
  LatestReader<Health> health(
      {std::string(kService), std::string(kHubInstance), std::string(kHealthEvent)});
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!health.latest() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  if (!health.latest()) return std::nullopt;
  return health.latest()->free_publisher_ports;
}

void count_publisher_ports_from(std::optional<std::uint32_t> free) {
  g_ports_left = free ? static_cast<std::int64_t>(*free) : -1;
}

void require_publisher_ports(std::size_t count, const std::string& what) {
  const auto wanted = static_cast<std::int64_t>(count);
  // Near the end, counted afresh: other processes take and give back ports too.
  if (g_ports_left >= 0 && g_ports_left < wanted + kRecountBelow)
    count_publisher_ports_from(free_publisher_ports(std::chrono::milliseconds(500)));
  const std::int64_t left = g_ports_left;
  if (left >= 0 && left < wanted) throw Error(ports_message(count, left, what));
}

void took_publisher_port() noexcept {
  if (g_ports_left > 0) --g_ports_left;
}

void gave_back_publisher_port() noexcept {
  if (g_ports_left >= 0) ++g_ports_left;
}

}  // namespace afhub
