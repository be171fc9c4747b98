// The renderings of `afhub ls` and `afhub status` (see listings.hpp).
#include "listings.hpp"

#include <cstdarg>
#include <cstdio>
#include <cstring>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/json_writer.hpp"
#include "format.hpp"
#include "loop_table.hpp"

namespace afhub::cli {
namespace {

// printf onto the end of `out`.
[[gnu::format(printf, 2, 3)]] void appendf(std::string& out, const char* format, ...) {
  char line[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(line, sizeof line, format, args);
  va_end(args);
  out += line;
}

}  // namespace

std::string ls_text(const BodyList& catalog) {
  if (catalog.body_count == 0)
    return "no bodies are published yet (start a simulation with `afhub run`, or `afhub synth`)\n";
  std::string out;
  appendf(out, "%-40s %10s %6s  %s\n", "BODY", "RATE_HZ", "JOINTS", "OWNER");
  for (std::uint32_t i = 0; i < catalog.body_count; ++i) {
    const BodyInfo& body = catalog.bodies[i];
    // A device has no joints: the column says what it is instead.
    const std::string joints =
        body.kind == ChannelKind::kDevice ? "device" : std::to_string(body.joint_count);
    appendf(out, "%-40s %10s %6s  %s (pid %u)\n", std::string(name_of(body.channel)).c_str(),
            rate_text(body.publish_rate_hz).c_str(), joints.c_str(),
            std::string(name_of(body.owner)).c_str(), body.owner_pid);
  }
  return out;
}

std::string ls_json(const BodyList& catalog) {
  JsonWriter json;
  json.begin_array();
  for (std::uint32_t i = 0; i < catalog.body_count; ++i) {
    const BodyInfo& body = catalog.bodies[i];
    json.begin_object();
    json.key("body").value(name_of(body.channel));
    // null until the hub has measured the rate (its first seconds).
    json.key("rate_hz");
    if (rate_measured(body.publish_rate_hz))
      json.value(body.publish_rate_hz);
    else
      json.null();
    json.key("owner").value(name_of(body.owner));
    json.key("owner_pid").value(static_cast<long long>(body.owner_pid));
    json.key("kind").value(body.kind == ChannelKind::kDevice ? "device" : "body");
    json.key("joints").begin_array();
    for (const std::string& name : joint_names_of(catalog, body)) json.value(name);
    json.end_array().end_object();
  }
  json.end_array();
  return json.str();
}

std::string status_json(const Health& health, const BodyList& catalog, const WorldState* world,
                        const std::vector<LoopStats>& loops) {
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
  for (std::uint32_t i = 0; i < catalog.body_count; ++i) {
    json.begin_object().key("body").value(name_of(catalog.bodies[i].channel)).key("rate_hz");
    if (rate_measured(catalog.bodies[i].publish_rate_hz))
      json.value(catalog.bodies[i].publish_rate_hz);
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
        .key("paused_by_pid")
        .value(static_cast<unsigned long long>(world->paused_by_pid))
        .key("pause_held")
        .value(world->pause_held != 0)
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
  return json.str();
}

std::string status_text(const Health& health, const BodyList& catalog, const WorldState* world,
                        const std::vector<LoopStats>& loops) {
  // Whose pause, and whether it lapses once its holder goes quiet (WorldCommand.hold_ms).
  const auto pause_text = [](const WorldState& state) -> std::string {
    if (!state.paused) return "";
    if (state.paused_by_pid == 0) return " (paused)";
    return " (paused by pid " + std::to_string(state.paused_by_pid) +
           (state.pause_held ? ", a held pause: it lapses once that process goes quiet)" : ")");
  };
  std::string out;
  appendf(out, "hub: pid %u, up %.1f s, %u bodies, %u processes\n", health.header.publisher_pid,
          health.hub_uptime_s, health.body_count, health.process_count);
  if (world)
    appendf(out,
            "world: step %llu, sim time %.3f s, %.1f steps/s%s, %llu commands refused, %llu "
            "stale, %llu watchdog expiries\n",
            static_cast<unsigned long long>(world->header.sim_step), world->header.sim_time_s,
            world->achieved_rate_hz, pause_text(*world).c_str(),
            static_cast<unsigned long long>(world->rejected_commands),
            static_cast<unsigned long long>(world->stale_commands),
            static_cast<unsigned long long>(world->watchdog_expiries));
  if (world && world->nan_recoveries > 0)
    appendf(out,
            "nan: %llu bodies put back after a step made them NaN or infinite; last: %.*s at "
            "step %llu\n",
            static_cast<unsigned long long>(world->nan_recoveries),
            static_cast<int>(strnlen(world->last_nan_body.data(), world->last_nan_body.size())),
            world->last_nan_body.data(), static_cast<unsigned long long>(world->last_nan_step));
  if (world && world->commanded_steps > 0)
    appendf(out,
            "commands: %llu steps under command, %llu late (the command answered an older "
            "state), %.1f %%\n",
            static_cast<unsigned long long>(world->commanded_steps),
            static_cast<unsigned long long>(world->commanded_steps - world->answered_steps),
            100.0 * static_cast<double>(world->commanded_steps - world->answered_steps) /
                static_cast<double>(world->commanded_steps));
  if (world && world->lockstep)
    appendf(out, "lockstep: %u clients in the barrier, %llu late answers, %llu clients dropped\n",
            world->lockstep_clients, static_cast<unsigned long long>(world->late_answers),
            static_cast<unsigned long long>(world->dropped_clients));
  out += "\nprocesses:\n";
  for (std::uint32_t i = 0; i < health.process_count; ++i)
    appendf(out, "  %-40s pid %d\n", std::string(name_of(health.processes[i].name)).c_str(),
            health.processes[i].pid);
  out += "\nbodies:\n";
  for (std::uint32_t i = 0; i < catalog.body_count; ++i)
    appendf(out, "  %-40s %8s Hz\n", std::string(name_of(catalog.bodies[i].channel)).c_str(),
            rate_text(catalog.bodies[i].publish_rate_hz).c_str());
  if (!loops.empty()) out += "\nloops:\n" + loop_table(loops);
  out += "\nmempools: segment  chunk bytes     chunks       used   min free\n";
  for (std::uint32_t i = 0; i < health.mempool_count; ++i) {
    const MempoolUsage& pool = health.mempools[i];
    appendf(out, "          %7u %12u %10u %10u %10u\n", pool.segment_id, pool.chunk_payload_bytes,
            pool.chunk_count, pool.used_chunks, pool.min_free_chunks);
  }
  return out;
}

}  // namespace afhub::cli
