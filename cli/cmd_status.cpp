// `afhub status`: the hub's health (processes, bodies, mempool usage) and, when a
// simulation runs, its world state (clock, rate, refused commands, watchdog expiries,
// lockstep), and the timing of every loop (as `afhub top` shows it).
#include <cstdio>
#include <memory>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/loop_stats_reader.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/health.hpp"
#include "afhub/shm_layout/world.hpp"
#include "commands.hpp"
#include "listings.hpp"

namespace afhub::cli {
namespace {

struct StatusOptions {
  bool json = false;
};

const Health& wait_for_health(LatestReader<Health>& reader) {
  auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(1500);
  while (!reader.latest()) {
    if (std::chrono::steady_clock::now() > deadline)
      throw Error(
          "a RouDi answers but publishes no afhub health: it is not an afhub hub (a plain "
          "iox-roudi?). Stop it and start `afhub hub`.");
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return *reader.latest();
}

int run_status(const StatusOptions& options) {
  connect_to_hub("status", HubPolicy::kRequire);
  LatestReader<Health> reader(
      {std::string(kService), std::string(kHubInstance), std::string(kHealthEvent)});
  const Health& health = wait_for_health(reader);
  CatalogReader catalog;
  catalog.wait(std::chrono::milliseconds(1000));
  const BodyList& bodies = catalog.latest();
  // A running simulation's world state arrives at once (publisher history); allow a moment.
  LatestReader<WorldState> world_reader(
      {std::string(kService), std::string(kWorldInstance), std::string(kStateEvent)});
  const auto world_deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(100);
  while (!world_reader.latest() && std::chrono::steady_clock::now() < world_deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  const WorldState* world = world_reader.latest();
  LoopStatsReader loop_reader;
  const std::vector<LoopStats> loops = loop_reader.all(std::chrono::seconds(2));
  if (options.json)
    std::printf("%s\n", status_json(health, bodies, world, loops).c_str());
  else
    std::printf("%s", status_text(health, bodies, world, loops).c_str());
  return 0;
}

}  // namespace

void register_status(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<StatusOptions>();
  auto* status =
      app.add_subcommand("status", "Show the hub's health: processes, bodies, mempool usage.");
  status->add_flag("--json", options->json, "Print one JSON object.");
  status->callback([&selected, options] { selected = [options] { return run_status(*options); }; });
}

}  // namespace afhub::cli
