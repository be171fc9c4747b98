// The bench's outputs: the --json document, the table on stdout and the --plot PNG.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "afhub/bench/bench.hpp"
#include "afhub/hub/json_writer.hpp"
#include "afhub/rt/percentile.hpp"
#include "afhub/shm_layout/error.hpp"
#include "child_process.hpp"
#include "text_format.hpp"

namespace afhub::bench {
namespace {

std::string size_label(std::uint32_t bytes) {
  if (bytes >= (1u << 20)) return std::to_string(bytes >> 20) + " MiB";
  if (bytes >= (1u << 10)) return std::to_string(bytes >> 10) + " KiB";
  return std::to_string(bytes) + " B";
}

void write_distribution(JsonWriter& json, const Distribution& d, bool with_p90, const char* unit) {
  const std::string u = unit;
  json.begin_object();
  json.key("p50" + u).value(d.p50_us);
  if (with_p90) json.key("p90" + u).value(d.p90_us);
  json.key("p99" + u).value(d.p99_us);
  json.key("p999" + u).value(d.p999_us);
  json.key("max" + u).value(d.max_us);
  json.key("samples").value(static_cast<unsigned long long>(d.samples));
  json.end_object();
}

void write_transports(JsonWriter& json, const BenchResults& results,
                      std::map<std::uint32_t, std::vector<double>> TransportResult::*samples) {
  json.begin_object();
  for (const TransportResult& transport : results.transports) {
    if (!transport.skipped.empty()) continue;
    json.key(transport.name).begin_object();
    for (const auto& [bytes, values] : transport.*samples) {
      json.key(std::to_string(bytes));
      write_distribution(json, summarize(values), true, "_us");
    }
    json.end_object();
  }
  json.end_object();
}

const TransportResult* find(const BenchResults& results, const std::string& name) {
  for (const TransportResult& transport : results.transports)
    if (transport.name == name && transport.skipped.empty()) return &transport;
  return nullptr;
}

// The one-way latency of a transport at a size; all zero when not measured.
Distribution one_way_of(const BenchResults& results, const std::string& name, std::uint32_t bytes) {
  const TransportResult* transport = find(results, name);
  if (!transport || !transport->one_way_us.count(bytes)) return {};
  return summarize(transport->one_way_us.at(bytes));
}

double median_of(const BenchResults& results, const std::string& name, std::uint32_t bytes) {
  return one_way_of(results, name, bytes).p50_us;
}

}  // namespace

BenchOptions quick_options(BenchOptions options) {
  options.rounds = 5;
  options.pings_per_round = 200;
  options.warmup_pings = 100;
  options.loop_seconds = 20.0;
  return options;
}

std::string results_json(const BenchResults& results) {
  JsonWriter json;
  json.begin_object();
  json.key("machine").begin_object();
  json.key("cpu").value(results.machine.cpu);
  json.key("cores").value(static_cast<unsigned long long>(results.machine.cores));
  json.key("memory_gib").value(results.machine.memory_gib);
  json.key("kernel").value(results.machine.kernel);
  json.key("os").value(results.machine.os);
  json.key("date").value(results.machine.date);
  json.end_object();
  json.key("settings").begin_object();
  json.key("rounds").value(static_cast<unsigned long long>(results.options.rounds));
  json.key("pings_per_round")
      .value(static_cast<unsigned long long>(results.options.pings_per_round));
  json.key("warmup_pings").value(static_cast<unsigned long long>(results.options.warmup_pings));
  json.key("loop_seconds").value(results.options.loop_seconds);
  json.key("fifo_priority").value(static_cast<long long>(results.options.fifo_priority));
  json.key("touch").value(results.options.touch);
  json.end_object();
  json.key("transports");  // one-way latency
  write_transports(json, results, &TransportResult::one_way_us);
  json.key("round_trip");
  write_transports(json, results, &TransportResult::round_trip_us);
  json.key("skipped").begin_object();
  for (const TransportResult& transport : results.transports)
    if (!transport.skipped.empty()) json.key(transport.name).value(transport.skipped);
  if (!results.loop.skipped.empty()) json.key("loop").value(results.loop.skipped);
  if (!results.loop.cyclictest_skipped.empty())
    json.key("cyclictest").value(results.loop.cyclictest_skipped);
  json.end_object();
  json.key("loop_jitter").begin_object();
  const bool loop_ran = results.loop.skipped.empty();
  json.key("afhub_us");
  if (loop_ran)
    write_distribution(json, summarize(results.loop.controller_wake), false, "");
  else
    json.null();
  json.key("cyclictest_us");
  if (loop_ran && results.loop.cyclictest_skipped.empty()) {
    write_distribution(json, summarize(results.loop.cyclictest_wake), false, "");
  } else {
    json.null();
  }
  json.end_object();
  json.key("loop_deadline_hit_ratio");
  if (loop_ran)
    json.value(results.loop.deadline_hit_ratio());
  else
    json.null();
  json.key("loop_steps").value(static_cast<unsigned long long>(results.loop.commanded_steps));
  json.end_object();
  return json.str() + "\n";
}

std::string results_table(const BenchResults& results) {
  std::string out = results.options.touch
                        ? "Messages: every byte written by the sender and read by the receiver "
                          "(--touch)\n\n"
                        : "Messages: the stamps written and read, the rest left as it is (the "
                          "iceperf convention; --touch writes and reads every byte)\n\n";
  const auto row = [&](const std::string& name, const std::vector<std::string>& cells) {
    char head[32];
    std::snprintf(head, sizeof head, "%-8s", name.c_str());
    out += head;
    for (const std::string& cell : cells) {
      char padded[32];
      std::snprintf(padded, sizeof padded, "%20s", cell.c_str());
      out += padded;
    }
    out += "\n";
  };
  std::vector<std::string> sizes;
  for (std::uint32_t bytes : kPayloadSizes) sizes.push_back(size_label(bytes));
  for (const auto& [title, quantile] :
       {std::pair<const char*, double>{"median", 0.5}, {"p99", 0.99}}) {
    out += std::string("One-way latency, ") + title + " in us (x: times afhub's)\n";
    row("", sizes);
    for (const TransportResult& transport : results.transports) {
      if (!transport.skipped.empty()) {
        out += transport.name + "    skipped: " + transport.skipped + "\n";
        continue;
      }
      std::vector<std::string> cells;
      for (std::uint32_t bytes : kPayloadSizes) {
        std::vector<double> sorted = transport.one_way_us.at(bytes);
        std::sort(sorted.begin(), sorted.end());
        const double value = percentile_of_sorted<double>(sorted, quantile);
        const TransportResult* afhub = find(results, "afhub");
        std::string cell = format("%.1f", value);
        if (afhub && afhub != &transport) {
          std::vector<double> base = afhub->one_way_us.at(bytes);
          std::sort(base.begin(), base.end());
          cell += format(" (%.1fx)", value / percentile_of_sorted<double>(base, quantile));
        }
        cells.push_back(cell);
      }
      row(transport.name, cells);
    }
    out += "\n";
  }

  const LoopResult& loop = results.loop;
  if (!loop.skipped.empty()) {
    out += "1 kHz loop: skipped: " + loop.skipped + "\n";
  } else {
    out += format("1 kHz loop beside the physics, %.0f s: wake-up latency in us\n", loop.seconds);
    row("", {"p50", "p99", "p99.9", "max", "samples"});
    const auto loop_row = [&](const std::string& name, Distribution d) {
      row(name, {format("%.0f", d.p50_us), format("%.0f", d.p99_us), format("%.0f", d.p999_us),
                 format("%.0f", d.max_us), std::to_string(d.samples)});
    };
    loop_row("afhub", summarize(loop.controller_wake));
    if (loop.cyclictest_skipped.empty()) {
      loop_row("cyclic", summarize(loop.cyclictest_wake));
    } else {
      out += "cyclictest skipped: " + loop.cyclictest_skipped + "\n";
    }
    out += format("Commands in time for the next step: %.2f %% of %.0f steps\n",
                  100.0 * loop.deadline_hit_ratio(), static_cast<double>(loop.commanded_steps));
    out += late_commands_text(loop.late, 1);  // one body commanded
  }

  // The goals this machine is held to, met or not.
  out += "\nGoals\n";
  const double afhub_1k = median_of(results, "afhub", 1024);
  for (const auto& [name, goal] :
       {std::pair<const char*, double>{"dds", 3.0}, {"uds", 1.5}, {"ros1", 10.0}}) {
    const double other = median_of(results, name, 1024);
    if (afhub_1k <= 0.0 || other <= 0.0) continue;
    out += format("  1 KiB median, afhub %.2f us vs ", afhub_1k) + name +
           format(" %.2f us: %.1fx lower (goal %.1fx): ", other, other / afhub_1k, goal) +
           (other / afhub_1k >= goal ? "met\n" : "NOT met\n");
  }
  // States and commands travel through slots: their own goals.
  const double slot_1k = median_of(results, "afhub-slot", 1024);
  const double slot_1k_p99 = one_way_of(results, "afhub-slot", 1024).p99_us;
  if (slot_1k > 0.0) {
    out += format(
               "  1 KiB through a slot (states, commands): median %.2f us (goal <= 0.4 us), "
               "p99 %.2f us (goal <= 1 us): ",
               slot_1k, slot_1k_p99) +
           (slot_1k <= 0.4 && slot_1k_p99 <= 1.0 ? "met\n" : "NOT met\n");
    // The same messages over bare shared memory in the same seconds: what this machine
    // allows any shared-memory transport. Only when both move every byte: without --touch
    // the floor moves one cache line, where the slot's reader copies the whole payload.
    const Distribution floor = one_way_of(results, "shm-floor", 1024);
    if (floor.p50_us > 0.0 && results.options.touch)
      out += format(
                 "  1 KiB, afhub-slot against shm-floor (bare shared memory, the machine's "
                 "floor, %.2f us / %.2f us): median %.2fx, p99 %.2fx the floor",
                 floor.p50_us, floor.p99_us, slot_1k / floor.p50_us, slot_1k_p99 / floor.p99_us) +
             (floor.p50_us > 0.4 ? "; the 0.4 us goal is below it on this machine\n" : "\n");
    for (const auto& [name, goal] :
         {std::pair<const char*, double>{"dds", 75.0}, {"uds", 5.0}, {"ros1", 100.0}}) {
      const double other = median_of(results, name, 1024);
      if (other <= 0.0) continue;
      out += format("  1 KiB median, afhub-slot %.2f us vs ", slot_1k) + name +
             format(" %.2f us: %.1fx lower (goal %.0fx): ", other, other / slot_1k, goal) +
             (other / slot_1k >= goal ? "met\n" : "NOT met\n");
    }
    if (const double shm = median_of(results, "dds-shm", 1024); shm > 0.0)
      out += format(
          "  1 KiB median, afhub-slot %.2f us vs dds-shm %.2f us: %.1fx lower (no goal "
          "set: Cyclone DDS with its own shared memory)\n",
          slot_1k, shm, shm / slot_1k);
  }
  const double afhub_1m = median_of(results, "afhub", 1u << 20);
  if (afhub_1k > 0.0 && afhub_1m > 0.0)
    out += format("  zero copy: afhub median at 1 MiB is %.2fx its median at 1 KiB (goal <= 2): ",
                  afhub_1m / afhub_1k) +
           (afhub_1m / afhub_1k <= 2.0 ? "met\n" : "NOT met\n");
  if (loop.skipped.empty())
    out += format("  commands in time for the next step %.1f %% (goal >= %.0f %%): ",
                  100.0 * loop.deadline_hit_ratio(), 100.0 * kInTimeGoal) +
           (loop.deadline_hit_ratio() >= kInTimeGoal ? "met\n" : "NOT met\n");
  if (loop.skipped.empty() && loop.cyclictest_skipped.empty()) {
    const double mine = loop.controller_wake.percentile_us(0.99);
    const double floor = loop.cyclictest_wake.percentile_us(0.99);
    out += format("  loop p99 wake-up %.0f us vs cyclictest %.0f us: %.2fx (goal <= 2): ", mine,
                  floor, mine / floor) +
           (mine <= 2.0 * floor ? "met\n" : "NOT met\n");
  }
  return out;
}

std::vector<std::string> failures(const BenchResults& results) {
  const LoopResult& loop = results.loop;
  std::vector<std::string> found;
  if (!loop.skipped.empty()) return found;
  if (!loop.physics_dropped.empty())
    found.push_back("the physics did not publish every step's states: it said \"" +
                    loop.physics_dropped + "\"");
  if (loop.deadline_hit_ratio() < kMinInTimeRatio)
    found.push_back(
        format("%.1f %% of the commands came in time for the next step (below %.0f "
               "%%): the loop's figures are not those of a working controller",
               100.0 * loop.deadline_hit_ratio(), 100.0 * kMinInTimeRatio));
  return found;
}

std::vector<std::pair<double, std::uint64_t>> histogram_rows(const LatencyHistogram& h) {
  std::map<std::int64_t, std::uint64_t> counts;  // by upper edge, ns
  const std::size_t last =
      std::min(LatencyHistogram::bin_of(h.max_ns()), LatencyHistogram::kBins - 1);
  for (std::size_t bin = 0; bin <= last; ++bin) {
    const std::int64_t edge = LatencyHistogram::highest_ns(bin) + 1;
    counts[edge < 128'000 ? (edge + 999) / 1000 * 1000 : edge] += h.bin_count(bin);
  }
  std::vector<std::pair<double, std::uint64_t>> rows;
  for (const auto& [edge, count] : counts)
    rows.emplace_back(static_cast<double>(edge) * 1e-3, count);
  return rows;
}

void write_plot(const BenchResults& results, const std::string& png_path) {
  if (access("/usr/bin/gnuplot", X_OK) != 0)
    throw Error("--plot needs gnuplot: install Debian's gnuplot-nox");
  char folder[] = "/tmp/afhub-bench-plot-XXXXXX";
  if (!mkdtemp(folder)) throw Error("cannot make a folder for the plot's data in /tmp");
  const std::string dir = folder;
  std::ofstream script(dir + "/plot.gp");
  script << "set terminal pngcairo size 1800,1000 font ',11'\n"
         << "set output '" << png_path << "'\n"
         << "set multiplot layout 2,3 title 'afhub bench on " << results.machine.cpu << ", "
         << results.machine.cores << " cores, " << results.machine.date << "'\n"
         << "set grid\nset key bottom right\nset logscale x\n"
         << "set xlabel 'one-way latency (us)'\nset ylabel 'fraction of samples'\n";
  for (std::uint32_t bytes : kPayloadSizes) {
    script << "set title 'one-way latency CDF, " << size_label(bytes) << "'\nplot ";
    bool first = true;
    for (const TransportResult& transport : results.transports) {
      if (!transport.skipped.empty()) continue;
      std::vector<double> sorted = transport.one_way_us.at(bytes);
      std::sort(sorted.begin(), sorted.end());
      const std::string data = dir + "/" + transport.name + "-" + std::to_string(bytes) + ".dat";
      std::ofstream out(data);
      const std::size_t step = std::max<std::size_t>(1, sorted.size() / 2000);
      for (std::size_t i = 0; i < sorted.size(); i += step)
        out << sorted[i] << " " << static_cast<double>(i + 1) / sorted.size() << "\n";
      out << sorted.back() << " 1\n";
      script << (first ? "" : ", ") << "'" << data << "' with lines lw 2 title '" << transport.name
             << "'";
      first = false;
    }
    script << "\n";
  }
  const LoopResult& loop = results.loop;
  // Wake-up histograms on a log-log scale, so that the tail shows beside the bulk.
  script << "set logscale xy\nset yrange [0.7:*]\nset key top right\n"
         << "set title '1 kHz loop wake-up latency'\nset xlabel 'wake-up latency (us)'\n"
         << "set ylabel 'cycles per bin'\n";
  if (loop.skipped.empty()) {
    const auto histogram = [&](const LatencyHistogram& h, const std::string& file,
                               const std::string& title) {
      const std::string data = dir + "/loop-" + file + ".dat";
      std::ofstream out(data);
      for (const auto& [edge_us, count] : histogram_rows(h)) out << edge_us << " " << count << "\n";
      return "'" + data + "' with steps lw 2 title '" + title + "'";
    };
    script << "plot " << histogram(loop.controller_wake, "afhub", "afhub controller");
    if (loop.cyclictest_skipped.empty())
      script << ", " << histogram(loop.cyclictest_wake, "cyclictest", "cyclictest");
    script << "\n";
  }
  script << "unset multiplot\n";
  script.close();
  ChildProcess gnuplot({"gnuplot", dir + "/plot.gp"}, dir + "/gnuplot.log");
  const int code = gnuplot.wait(60'000);
  if (code != 0)
    throw Error("gnuplot failed (exit " + std::to_string(code) + "); see " + dir + "/gnuplot.log");
  std::filesystem::remove_all(dir);
}

}  // namespace afhub::bench
