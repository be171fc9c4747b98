// `afhub status`: the hub's health (processes, bodies, mempool usage) and, when a
// simulation runs, its world state (clock, rate, refused commands, watchdog expiries,
// lockstep), and the timing of every loop (as `afhub top` shows it).
#include <cstdio>
#include <memory>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/json_writer.hpp"
#include "afhub/hub/loop_stats_reader.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/health.hpp"
#include "afhub/shm_layout/world.hpp"
#include "commands.hpp"
#include "format.hpp"
#include "loop_table.hpp"

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
  // Loops found now deliver their last stats (history) once subscribed: a moment.
  LoopStatsReader loop_reader;
  std::vector<LoopStats> loops = loop_reader.latest();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  loops = loop_reader.latest();
  if (options.json) {
    JsonWriter json;
    json.begin_object();
    json.key("hub_pid").value(static_cast<long long>(health.header.publisher_pid));
    json.key("uptime_s").value(health.hub_uptime_s);
    json.key("body_count").value(static_cast<long long>(health.body_count));
    json.key("processes").begin_array();
    for (std::uint32_t i = 0; i < health.process_count; ++i)
      json.begin_object()
          .key("name")
          .value(name_of(health.processes[i].name))
          .key("pid")
          .value(static_cast<long long>(health.processes[i].pid))
          .end_object();
    json.end_array();
    json.key("bodies").begin_array();
    for (std::uint32_t i = 0; i < bodies.body_count; ++i) {
      json.begin_object().key("body").value(name_of(bodies.bodies[i].channel)).key("rate_hz");
      if (rate_measured(bodies.bodies[i].publish_rate_hz))
        json.value(bodies.bodies[i].publish_rate_hz);
      else
        json.null();  // not measured yet
      json.end_object();
    }
    json.end_array();
    json.key("world");
    if (world) {
      json.begin_object()
          .key("sim_step")
          .value(static_cast<unsigned long long>(world->header.sim_step))
          .key("sim_time_s")
          .value(world->header.sim_time_s)
          .key("rate_hz")
          .value(world->achieved_rate_hz)
          .key("paused")
          .value(world->paused != 0)
          .key("rejected_commands")
          .value(static_cast<unsigned long long>(world->rejected_commands))
          .key("watchdog_expiries")
          .value(static_cast<unsigned long long>(world->watchdog_expiries))
          .key("stale_commands")
          .value(static_cast<unsigned long long>(world->stale_commands))
          .key("nan_recoveries")
          .value(static_cast<unsigned long long>(world->nan_recoveries))
          .key("commanded_steps")
          .value(static_cast<unsigned long long>(world->commanded_steps))
          .key("answered_steps")
          .value(static_cast<unsigned long long>(world->answered_steps))
          .key("late_steps")
          .value(static_cast<unsigned long long>(world->commanded_steps - world->answered_steps))
          .key("lockstep")
          .value(world->lockstep != 0)
          .key("lockstep_clients")
          .value(static_cast<long long>(world->lockstep_clients))
          .key("late_answers")
          .value(static_cast<unsigned long long>(world->late_answers))
          .key("dropped_clients")
          .value(static_cast<unsigned long long>(world->dropped_clients))
          .end_object();
    } else {
      json.begin_object().end_object();
    }
    json.key("loops");
    loop_json(json, loops);
    json.key("mempools").begin_array();
    for (std::uint32_t i = 0; i < health.mempool_count; ++i) {
      const MempoolUsage& pool = health.mempools[i];
      json.begin_object()
          .key("segment")
          .value(static_cast<long long>(pool.segment_id))
          .key("chunk_payload_bytes")
          .value(static_cast<long long>(pool.chunk_payload_bytes))
          .key("chunks")
          .value(static_cast<long long>(pool.chunk_count))
          .key("used")
          .value(static_cast<long long>(pool.used_chunks))
          .key("min_free")
          .value(static_cast<long long>(pool.min_free_chunks))
          .end_object();
    }
    json.end_array().end_object();
    std::printf("%s\n", json.str().c_str());
    return 0;
  }
  std::printf("hub: pid %u, up %.1f s, %u bodies, %u processes\n", health.header.publisher_pid,
              health.hub_uptime_s, health.body_count, health.process_count);
  if (world)
    std::printf(
        "world: step %llu, sim time %.3f s, %.1f steps/s%s, %llu commands refused, %llu stale, "
        "%llu watchdog expiries\n",
        static_cast<unsigned long long>(world->header.sim_step), world->header.sim_time_s,
        world->achieved_rate_hz, world->paused ? " (paused)" : "",
        static_cast<unsigned long long>(world->rejected_commands),
        static_cast<unsigned long long>(world->stale_commands),
        static_cast<unsigned long long>(world->watchdog_expiries));
  if (world && world->nan_recoveries > 0)
    std::printf(
        "nan: %llu bodies put back after a step made them NaN or infinite; last: %s at "
        "step %llu\n",
        static_cast<unsigned long long>(world->nan_recoveries), world->last_nan_body.data(),
        static_cast<unsigned long long>(world->last_nan_step));
  if (world && world->commanded_steps > 0)
    std::printf(
        "commands: %llu steps under command, %llu late (the command answered an older state), "
        "%.1f %%\n",
        static_cast<unsigned long long>(world->commanded_steps),
        static_cast<unsigned long long>(world->commanded_steps - world->answered_steps),
        100.0 * static_cast<double>(world->commanded_steps - world->answered_steps) /
            static_cast<double>(world->commanded_steps));
  if (world && world->lockstep)
    std::printf("lockstep: %u clients in the barrier, %llu late answers, %llu clients dropped\n",
                world->lockstep_clients, static_cast<unsigned long long>(world->late_answers),
                static_cast<unsigned long long>(world->dropped_clients));
  std::printf("\nprocesses:\n");
  for (std::uint32_t i = 0; i < health.process_count; ++i)
    std::printf("  %-40s pid %d\n", std::string(name_of(health.processes[i].name)).c_str(),
                health.processes[i].pid);
  std::printf("\nbodies:\n");
  for (std::uint32_t i = 0; i < bodies.body_count; ++i)
    std::printf("  %-40s %8s Hz\n", std::string(name_of(bodies.bodies[i].channel)).c_str(),
                rate_text(bodies.bodies[i].publish_rate_hz).c_str());
  if (!loops.empty()) std::printf("\nloops:\n%s", loop_table(loops).c_str());
  std::printf("\nmempools: segment  chunk bytes     chunks       used   min free\n");
  for (std::uint32_t i = 0; i < health.mempool_count; ++i) {
    const MempoolUsage& pool = health.mempools[i];
    std::printf("          %7u %12u %10u %10u %10u\n", pool.segment_id, pool.chunk_payload_bytes,
                pool.chunk_count, pool.used_chunks, pool.min_free_chunks);
  }
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
