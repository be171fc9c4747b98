// Rendering of loop stats (see loop_table.hpp).
#include "loop_table.hpp"

#include <cstdio>

#include "afhub/hub/bodies.hpp"

namespace afhub::cli {
namespace {

std::string realtime_flags(const LoopStats& stats) {
  std::string flags = stats.lockstep ? "lockstep" : "";
  if (stats.realtime) flags += flags.empty() ? "fifo" : ",fifo";
  if (stats.memory_locked) flags += flags.empty() ? "mlock" : ",mlock";
  if (stats.cpu >= 0) flags += (flags.empty() ? "cpu" : ",cpu") + std::to_string(stats.cpu);
  if (stats.cpu_wake_latency_us >= 0)
    flags +=
        (flags.empty() ? "wake<=" : ",wake<=") + std::to_string(stats.cpu_wake_latency_us) + "us";
  return flags.empty() ? "-" : flags;
}

void percentiles(JsonWriter& json, const char* key, const DurationPercentiles& p) {
  json.key(key).begin_object();
  json.key("p50").value(p.p50_us).key("p99").value(p.p99_us);
  json.key("p99.9").value(p.p999_us).key("max").value(p.max_us);
  json.end_object();
}

}  // namespace

std::string loop_table(const std::vector<LoopStats>& loops) {
  std::string out =
      "  pid     loop        body                         rate Hz   wake us p50/p99/p99.9/max"
      "       compute us p99/max   overruns   late  settings\n";
  char line[512];
  for (const LoopStats& s : loops) {
    std::snprintf(line, sizeof line,
                  "  %-7u %-11s %-26s %9.1f   %6.0f %6.0f %6.0f %8.0f   %8.1f %8.0f   %8llu %6llu  "
                  "%s\n",
                  s.header.publisher_pid, std::string(name_of(s.name)).c_str(),
                  name_of(s.body).empty() ? "-" : std::string(name_of(s.body)).c_str(), s.rate_hz,
                  s.wake_latency.p50_us, s.wake_latency.p99_us, s.wake_latency.p999_us,
                  s.wake_latency.max_us, s.compute.p99_us, s.compute.max_us,
                  static_cast<unsigned long long>(s.overruns),
                  static_cast<unsigned long long>(s.late_commands), realtime_flags(s).c_str());
    out += line;
  }
  return out;
}

void loop_json(JsonWriter& json, const std::vector<LoopStats>& loops) {
  json.begin_array();
  for (const LoopStats& s : loops) {
    json.begin_object();
    json.key("pid").value(static_cast<long long>(s.header.publisher_pid));
    json.key("name").value(name_of(s.name));
    json.key("body").value(name_of(s.body));
    json.key("period_s").value(s.period_s);
    json.key("rate_hz").value(s.rate_hz);
    json.key("cycles").value(static_cast<unsigned long long>(s.cycles));
    json.key("overruns").value(static_cast<unsigned long long>(s.overruns));
    json.key("late_commands").value(static_cast<unsigned long long>(s.late_commands));
    percentiles(json, "wake_latency_us", s.wake_latency);
    percentiles(json, "compute_us", s.compute);
    json.key("realtime").value(s.realtime != 0);
    json.key("memory_locked").value(s.memory_locked != 0);
    json.key("lockstep").value(s.lockstep != 0);
    json.key("cpu").value(static_cast<long long>(s.cpu));
    json.key("cpu_wake_latency_us").value(static_cast<long long>(s.cpu_wake_latency_us));
    json.end_object();
  }
  json.end_array();
}

}  // namespace afhub::cli
