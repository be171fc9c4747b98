// The loop's wake-up latency by setting (see wake_bench.hpp).
#include "afhub/bench/wake_bench.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "afhub/rt/cpu_wake_latency.hpp"
#include "afhub/rt/periodic_loop.hpp"
#include "afhub/shm_layout/error.hpp"
#include "child_process.hpp"

namespace afhub::bench {
namespace {

constexpr std::int64_t kPeriodNs = 1'000'000;
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
      {"normal scheduler, the kernel's timer slack", 0, -1, 0},
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
  loop.period_ns = kPeriodNs;
  loop.fifo_priority = wanted.fifo_priority;
  loop.cpu_wake_latency_us = wanted.cpu_wake_latency_us;
  loop.timer_slack_ns = wanted.timer_slack_ns;
  loop.lock_memory = true;
  loop.max_cycles = static_cast<std::uint64_t>(std::llround(seconds * 1e9 / kPeriodNs));
  const RealtimeGrant grant = apply_realtime(loop, "afhub bench wake");
  if ((wanted.fifo_priority > 0 && !grant.realtime) ||
      (wanted.cpu_wake_latency_us >= 0 && grant.cpu_wake_latency_us < 0)) {
    std::printf("refused\n");
    return 0;
  }
  LoopTiming timing;
  run_periodic(loop, timing, [] { return true; });
  // The histogram's 1 us bins, and the exact maximum.
  const LatencyHistogram& wake = timing.wake_latency();
  std::printf("max %.3f\n", wake.max_us());
  for (std::size_t bin = 0; bin < LatencyHistogram::kBins; ++bin)
    if (const std::uint64_t count = wake.bin_count(bin))
      std::printf("%zu %llu\n", bin, static_cast<unsigned long long>(count));
  return 0;
}

WakeResults run_wake_bench(const WakeOptions& options) {
  const std::vector<WakeSetting>& settings = wake_settings();
  std::vector<LatencyHistogram> pooled(settings.size());
  std::vector<double> max_us(settings.size(), 0.0);
  WakeResults results;
  results.options = options;
  for (const WakeSetting& setting : settings) results.settings.push_back({setting, {}, {}});
  const std::string output = "/tmp/afhub-bench-wake-" + std::to_string(getpid()) + ".txt";
  for (std::uint32_t round = 1; round <= options.rounds; ++round) {
    std::fprintf(stderr, "afhub bench wake: round %u of %u\n", round, options.rounds);
    bool foreign_limit = false;
    for (std::size_t i = 0; i < settings.size(); ++i) {
      if (!results.settings[i].skipped.empty()) continue;
      if (settings[i].cpu_wake_latency_us < 0) {
        const std::int32_t limit = machine_limit_us();
        if (limit >= 0 && limit < 1000) foreign_limit = true;
      }
      ChildProcess peer({self_executable(), "bench", "wake", "--peer", std::to_string(i),
                         "--seconds", std::to_string(options.seconds)},
                        output);
      const int timeout_ms = static_cast<int>(options.seconds * 1000.0) + 10'000;
      if (const int code = peer.wait(timeout_ms); code != 0)
        throw Error("afhub bench wake: the loop of \"" + settings[i].name + "\" ended with " +
                    std::to_string(code) + "; see " + output);
      std::ifstream in(output);
      std::string line;
      while (std::getline(in, line)) {
        unsigned long long bin = 0, count = 0;
        double max = 0.0;
        if (line.rfind("refused", 0) == 0) {
          results.settings[i].skipped = "refused (needs root: SCHED_FIFO, /dev/cpu_dma_latency)";
        } else if (std::sscanf(line.c_str(), "max %lf", &max) == 1) {
          max_us[i] = std::max(max_us[i], max);
        } else if (std::sscanf(line.c_str(), "%llu %llu", &bin, &count) == 2) {
          for (unsigned long long k = 0; k < count; ++k)
            pooled[i].record(static_cast<double>(bin) + 0.5);
        }
      }
    }
    if (foreign_limit) ++results.rounds_with_foreign_limit;
  }
  std::remove(output.c_str());
  for (std::size_t i = 0; i < settings.size(); ++i) {
    results.settings[i].wake = summarize(pooled[i]);
    results.settings[i].wake.max_us = max_us[i];
  }
  return results;
}

std::string wake_table(const WakeResults& results) {
  char line[256];
  std::snprintf(line, sizeof line,
                "1 kHz loop wake-up latency (us): %u rounds of %.0f s per setting, interleaved\n"
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
    out += "note: in " + std::to_string(results.rounds_with_foreign_limit) +
           " rounds another process held the machine's CPU wake-up latency limit: the "
           "settings without --cpu-wake-latency ran on polling CPUs then\n";
  return out;
}

}  // namespace afhub::bench
