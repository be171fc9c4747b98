// Takes iceoryx subscriber ports until the hub's Health says only LEFT are free, the
// way a crowd of readers would, then holds them until SIGTERM. Its subscribers are
// iceoryx's own, not afhub readers: they ignore afhub's count, as another program's
// might. Prints "holding N subscriber ports, M free" when there.
// Usage: subscriber_port_taker LEFT
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "afhub/hub/channel.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/health.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: subscriber_port_taker LEFT\n");
    return 2;
  }
  const auto left = static_cast<std::uint32_t>(std::strtoul(argv[1], nullptr, 10));
  afhub::install_stop_signal_handlers();
  afhub::connect_to_hub("port-taker", afhub::HubPolicy::kRequire);
  afhub::LatestReader<afhub::Health> health({std::string(afhub::kService),
                                             std::string(afhub::kHubInstance),
                                             std::string(afhub::kHealthEvent)});
  std::vector<std::unique_ptr<iox::popo::UntypedSubscriber>> taken;
  const auto wait_for = [&](auto done) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (!(health.latest() && done(*health.latest()))) {
      if (std::chrono::steady_clock::now() > deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return true;
  };
  if (!wait_for([](const afhub::Health&) { return true; })) {
    std::fprintf(stderr, "subscriber_port_taker: no health from the hub\n");
    return 1;
  }
  // Near the end by the count, then the rest as the hub's health follows.
  for (int round = 0; health.latest()->free_subscriber_ports > left; ++round) {
    const std::uint32_t free = health.latest()->free_subscriber_ports;
    const std::uint32_t taking = free - left;
    for (std::uint32_t i = 0; i < taking; ++i) {
      const std::string instance = "taker" + std::to_string(taken.size());
      taken.push_back(std::make_unique<iox::popo::UntypedSubscriber>(iox::capro::ServiceDescription{
          "afhub-test", iox::capro::IdString_t(iox::cxx::TruncateToCapacity, instance.c_str()),
          "ports"}));
    }
    // A health published after these were taken (other processes give ports back
    // too): the loop takes what is still above LEFT.
    const std::int64_t taken_ns = afhub::monotonic_ns();
    if (round > 20 ||
        !wait_for([&](const afhub::Health& h) { return h.header.publish_stamp_ns > taken_ns; })) {
      std::fprintf(stderr, "subscriber_port_taker: the hub's health does not follow\n");
      return 1;
    }
  }
  std::printf("holding %zu subscriber ports, %u free\n", taken.size(),
              health.latest()->free_subscriber_ports);
  std::fflush(stdout);
  while (!afhub::stop_requested()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  return 0;
}
