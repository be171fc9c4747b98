// The loop's wake-up latency by setting (see wake_bench.hpp).
#include "afhub/bench/wake_bench.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>

#include "afhub/rt/cpu_wake_latency.hpp"
#include "afhub/rt/periodic_loop.hpp"
#include "afhub/rt/process_spawn.hpp"
#include "afhub/shm_layout/error.hpp"
#include "child_process.hpp"

namespace afhub::bench {
namespace {

constexpr std::int64_t kWakePeriodNs = 1'000'000;
constexpr int kFifoPriority = 80;

// The kernel's limit now, in us; -1 when it cannot be read.
std::int32_t machine_limit_us() {
  std::int32_t value = -1;
  std::ifstream(kCpuWakeLatencyDevice, std::ios::binary)
      .read(reinterpret_cast<char*>(&value), sizeof value);
  return value;
}

}  // namespace

const std::vector<WakeSetting>& wake_settings() {
  static const std::vector<WakeSetting> settings = {
      {"normal scheduler, the default timer slack", 0, -1, 0},
      {"normal scheduler (afhub: 1 ns timer slack)", 0, -1, 1},
      {"normal scheduler, --cpu-wake-latency 0", 0, 0, 1},
      {"--fifo 80", kFifoPriority, -1, 1},
      {"--fifo 80 --cpu-wake-latency 0", kFifoPriority, 0, 1},
  };
  return settings;
}

int run_wake_peer(std::size_t setting, double seconds) {
  if (setting >= wake_settings().size())
    throw Error("no wake-up setting " + std::to_string(setting));
  const WakeSetting& wanted = wake_settings()[setting];
  LoopOptions loop;
  loop.period_ns = kWakePeriodNs;
  loop.fifo_priority = wanted.fifo_priority;
  loop.cpu_wake_latency_us = wanted.cpu_wake_latency_us;
  loop.timer_slack_ns = wanted.timer_slack_ns;
  loop.max_cycles = static_cast<std::uint64_t>(std::llround(seconds * 1e9 / kWakePeriodNs));
  const RealtimeGrant grant = apply_realtime(loop, "afhub bench wake");
  if (wanted.fifo_priority > 0 && !grant.realtime) {
    std::printf("refused: SCHED_FIFO needs root, CAP_SYS_NICE or `ulimit -r`\n");
    return 0;
  }
  if (wanted.cpu_wake_latency_us >= 0 && grant.cpu_wake_latency_us < 0) {
    std::printf("refused: %s needs root\n", kCpuWakeLatencyDevice);
    return 0;
  }
  LoopTiming timing;
  run_periodic(loop, timing, [] { return true; });
  const LatencyHistogram& wake = timing.wake_latency();
  // The maximum, then "<a value of the bin, ns> <count>" per bin.
  std::printf("max %lld\n", static_cast<long long>(wake.max_ns()));
  for (std::size_t bin = 0; bin < LatencyHistogram::kBins; ++bin)
    if (const std::uint64_t count = wake.bin_count(bin))
      std::printf("%lld %llu\n", static_cast<long long>(LatencyHistogram::lowest_ns(bin)),
                  static_cast<unsigned long long>(count));
  if (const std::uint64_t count = wake.overflow())
    std::printf("%lld %llu\n", static_cast<long long>(wake.max_ns()),
                static_cast<unsigned long long>(count));
  return 0;
}

namespace {

std::string text_of(const std::string& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A file of this process's own for the loops' output, removed however the bench ends.
class OutputFile {
 public:
  OutputFile() {
    char path[] = "/tmp/afhub-bench-wake-XXXXXX";
    const int file = mkstemp(path);
    if (file < 0) throw Error(std::string("cannot create a file in /tmp: ") + std::strerror(errno));
    close(file);
    path_ = path;
  }
  ~OutputFile() { std::remove(path_.c_str()); }
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// Reads one loop's output into `result` (refused) or `pooled`.
void read_loop_output(const std::string& path, WakeResult& result, LatencyHistogram& pooled) {
  std::ifstream in(path);
  bool ran = false;
  for (std::string line; std::getline(in, line);) {
    long long ns = 0;
    unsigned long long count = 0;
    if (line.rfind("refused: ", 0) == 0) {
      result.skipped = "refused: " + line.substr(9);
      return;
    }
    if (std::sscanf(line.c_str(), "max %lld", &ns) == 1) {
      pooled.record(ns, 0);  // no sample: only the exact maximum
      ran = true;
    } else if (std::sscanf(line.c_str(), "%lld %llu", &ns, &count) == 2) {
      pooled.record(ns, count);  // into the same bin as in the loop
    }
  }
  if (!ran)
    throw Error("afhub bench wake: the loop of \"" + result.setting.name +
                "\" printed no latencies: " + text_of(path));
}

}  // namespace

WakeResults run_wake_bench(const WakeOptions& options) {
  const std::vector<WakeSetting>& settings = wake_settings();
  std::vector<LatencyHistogram> pooled(settings.size());
  WakeResults results;
  results.options = options;
  for (const WakeSetting& setting : settings) results.settings.push_back({setting, {}, {}});
  const OutputFile output;
  char seconds[32];
  std::snprintf(seconds, sizeof seconds, "%g", options.seconds);
  for (std::uint32_t round = 1; round <= options.rounds; ++round) {
    std::fprintf(stderr, "afhub bench wake: round %u of %u\n", round, options.rounds);
    bool foreign_limit = false;
    for (std::size_t i = 0; i < settings.size(); ++i) {
      if (!results.settings[i].skipped.empty()) continue;
      if (settings[i].cpu_wake_latency_us < 0) {
        const std::int32_t limit = machine_limit_us();
        if (limit >= 0 && limit <= kMaxCpuWakeLatencyUs) {
          foreign_limit = true;
          results.foreign_limit_us =
              std::min(results.foreign_limit_us < 0 ? limit : results.foreign_limit_us, limit);
        }
      }
      ChildProcess loop(
          {this_executable(), "bench", "wake", "--peer", std::to_string(i), "--seconds", seconds},
          output.path());
      const int timeout_ms = static_cast<int>(options.seconds * 1000.0) + 10'000;
      const int code = loop.wait(timeout_ms);
      if (code == -1)
        throw Error("afhub bench wake: the loop of \"" + settings[i].name +
                    "\" did not finish within " + std::to_string(timeout_ms / 1000) + " s");
      if (code != 0)
        throw Error("afhub bench wake: the loop of \"" + settings[i].name + "\" exited with " +
                    std::to_string(code) + ": " + text_of(output.path()));
      read_loop_output(output.path(), results.settings[i], pooled[i]);
    }
    if (foreign_limit) ++results.rounds_with_foreign_limit;
  }
  for (std::size_t i = 0; i < settings.size(); ++i) results.settings[i].wake = summarize(pooled[i]);
  return results;
}

std::string wake_table(const WakeResults& results) {
  char line[256];
  std::snprintf(line, sizeof line,
                "1 kHz loop wake-up latency (us): %u round(s) of %g s per setting, interleaved\n"
                "%-44s %8s %8s %8s %8s %8s\n",
                results.options.rounds, results.options.seconds, "setting", "p50", "p99", "p99.9",
                "max", "cycles");
  std::string out = line;
  for (const WakeResult& result : results.settings) {
    if (!result.skipped.empty()) {
      std::snprintf(line, sizeof line, "%-44s %s\n", result.setting.name.c_str(),
                    result.skipped.c_str());
    } else {
      const Distribution& d = result.wake;
      std::snprintf(line, sizeof line, "%-44s %8.0f %8.0f %8.0f %8.0f %8llu\n",
                    result.setting.name.c_str(), d.p50_us, d.p99_us, d.p999_us, d.max_us,
                    static_cast<unsigned long long>(d.samples));
    }
    out += line;
  }
  if (results.rounds_with_foreign_limit > 0)
    out += "note: when " + std::to_string(results.rounds_with_foreign_limit) +
           " of the rounds began, another process held the machine's CPU wake-up latency "
           "limit (at " +
           std::to_string(results.foreign_limit_us) +
           " us or less): the settings without --cpu-wake-latency ran under it\n";
  return out;
}

}  // namespace afhub::bench
