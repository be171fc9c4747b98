// The fault tests' eyes on a hub: a process of its own, since a test process that
// joined one hub's iceoryx runtime could never join the next (the runtime is a
// per-process singleton).
//   fault_probe attached TIMEOUT_MS BODY:PID...
//     Waits until every BODY is in the hub's catalog and commands published by PID
//     arrive on it (PID 0: the body alone). Prints "catalog BODY NS" and "command BODY NS"
//     (CLOCK_MONOTONIC) as each first holds; exit 0 when all hold, 1 at the timeout.
//   fault_probe chunks
//     Prints "BYTES:USED" for every payload mempool (its chunks' payload size, its
//     chunks in use), from a health sample counted after the probe started.
//   fault_probe hooked
//     Outlives the hub like a device driver: its make-safe hook prints "hook ran" on
//     stderr. Prints "attached N" (N: its re-attach count) on stdout, then waits for
//     SIGTERM.
#include <time.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/health.hpp"

namespace {

std::int64_t now_ns() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

void sleep_ms(int ms) {
  timespec pause{0, ms * 1'000'000L};
  nanosleep(&pause, nullptr);
}

struct Watched {
  std::string query;
  std::uint32_t pid = 0;
  std::string channel;  // once in the catalog
  std::unique_ptr<afhub::LatestReader<afhub::BodyCommand>> commands;
  bool commanded = false;
};

int attached(std::int64_t timeout_ms, std::vector<Watched>& bodies) {
  afhub::CatalogReader catalog;
  catalog.wait(std::chrono::milliseconds(2000));
  const std::int64_t give_up = now_ns() + timeout_ms * 1'000'000;
  for (;;) {
    bool all = true;
    for (Watched& body : bodies) {
      if (body.channel.empty()) {
        try {
          body.channel = std::string(afhub::name_of(catalog.resolve(body.query).info.channel));
          std::printf("catalog %s %lld\n", body.query.c_str(), static_cast<long long>(now_ns()));
          if (body.pid != 0)
            body.commands = std::make_unique<afhub::LatestReader<afhub::BodyCommand>>(
                afhub::body_command_channel(body.channel));
        } catch (const afhub::Error&) {
        }
      }
      if (!body.channel.empty() && body.pid != 0 && !body.commanded) {
        const afhub::BodyCommand* command = body.commands->latest();
        if (command && command->header.publisher_pid == body.pid) {
          body.commanded = true;
          std::printf("command %s %lld\n", body.query.c_str(), static_cast<long long>(now_ns()));
        }
      }
      all = all && !body.channel.empty() && (body.pid == 0 || body.commanded);
    }
    std::fflush(stdout);
    if (all) return 0;
    if (now_ns() > give_up) return 1;
    sleep_ms(2);
  }
}

// "BYTES:USED" per payload pool from the first health sample published after `after_ns`.
std::vector<std::string> chunks_in_use(afhub::LatestReader<afhub::Health>& health,
                                       std::int64_t after_ns) {
  std::vector<std::string> used;
  for (const std::int64_t give_up = now_ns() + 3'000'000'000; now_ns() < give_up; sleep_ms(10)) {
    const afhub::Health* sample = health.latest();
    if (!sample || sample->header.publish_stamp_ns <= after_ns || sample->mempool_count == 0)
      continue;
    for (std::uint32_t i = 0; i < sample->mempool_count; ++i)
      if (sample->mempools[i].segment_id != sample->mempools[0].segment_id)
        used.push_back(std::to_string(sample->mempools[i].chunk_payload_bytes) + ":" +
                       std::to_string(sample->mempools[i].used_chunks));
    break;
  }
  return used;
}

int chunks() {
  afhub::LatestReader<afhub::Health> health({"afhub", "hub", "health"});
  // RouDi's introspection counts the pools once a second and the hub publishes the
  // latest count: a sample published over a second after the probe started was counted
  // after it started. (Callers compare in a wait: a count may catch a chunk in flight.)
  const std::vector<std::string> used = chunks_in_use(health, now_ns() + 1'100'000'000);
  for (const std::string& pool : used) std::printf("%s ", pool.c_str());
  std::printf("\n");
  return used.empty() ? 1 : 0;
}

}  // namespace

int hooked() {
  afhub::install_stop_signal_handlers();
  afhub::survive_hub_loss("fault_probe");
  afhub::on_hub_lost([] {
    constexpr char kLine[] = "hook ran\n";
    (void)!write(STDERR_FILENO, kLine, sizeof kLine - 1);
  });
  afhub::connect_to_hub("faultprobe", afhub::HubPolicy::kRequire);
  std::printf("attached %u\n", afhub::reattach_count());
  std::fflush(stdout);
  while (!afhub::stop_requested()) sleep_ms(10);
  return 0;
}

int main(int argc, char** argv) {
  try {
    if (argc < 2) return 2;
    const std::string mode = argv[1];
    if (mode == "hooked") return hooked();
    afhub::connect_to_hub("faultprobe", afhub::HubPolicy::kRequire);
    if (mode == "chunks") return chunks();
    if (mode != "attached" || argc < 4) return 2;
    std::vector<Watched> bodies;
    for (int i = 3; i < argc; ++i) {
      const std::string item = argv[i];
      const auto colon = item.rfind(':');
      Watched body;
      body.query = item.substr(0, colon);
      body.pid = static_cast<std::uint32_t>(std::atol(item.c_str() + colon + 1));
      bodies.push_back(std::move(body));
    }
    return attached(std::atoll(argv[2]), bodies);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "fault_probe: %s\n", error.what());
    return 3;
  }
}
