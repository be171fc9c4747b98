// The bench's outputs from known results: the JSON document's shape and values,
// and the table's ratios and goal verdicts.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "afhub/bench/bench.hpp"
#include "strict_json.hpp"
#include "text_contains.hpp"

namespace afhub::bench {
namespace {

using nlohmann::json;

using afhub::test::contains;

// One-way latencies 1..100 us times `scale` at every size; round trips twice that.
TransportResult transport(const std::string& name, double scale) {
  TransportResult result;
  result.name = name;
  for (std::uint32_t bytes : kPayloadSizes)
    for (int i = 1; i <= 100; ++i) {
      result.one_way_us[bytes].push_back(i * scale);
      if (i % 2 == 0) result.round_trip_us[bytes].push_back(2 * i * scale);
    }
  return result;
}

BenchResults known_results() {
  BenchResults results;
  results.machine = {"Test CPU", "6.1", "Debian 12", "2026-11-21T00:00:00Z", 2, 24.0};
  results.transports.push_back(transport("afhub", 1.0));
  results.transports.push_back(transport("dds", 10.0));
  results.transports.push_back(transport("uds", 1.2));
  TransportResult ros1;
  ros1.name = "ros1";
  ros1.skipped = "not built";
  results.transports.push_back(ros1);
  results.loop.seconds = 20.0;
  results.loop.controller_wake.record(20'500, 990);  // ns
  results.loop.controller_wake.record(70'500, 10);
  results.loop.cyclictest_wake.record(19'000, 990);
  results.loop.cyclictest_wake.record(30'000, 10);
  results.loop.commanded_steps = 20000;
  results.loop.answered_steps = 19990;
  return results;
}

TEST(BenchReport, JsonHasTheDocumentedShape) {
  const json document = test::parse_json(results_json(known_results()));
  EXPECT_EQ(document.at("machine").at("cpu"), "Test CPU");
  EXPECT_EQ(document.at("machine").at("cores"), 2);

  const json& transports = document.at("transports");
  EXPECT_EQ(transports.size(), 3u);  // ros1 was skipped
  EXPECT_FALSE(transports.contains("ros1"));
  EXPECT_EQ(document.at("skipped").at("ros1"), "not built");
  for (const char* name : {"afhub", "dds", "uds"}) {
    const json& sizes = transports.at(name);
    ASSERT_EQ(sizes.size(), kPayloadSizes.size()) << name;
    for (std::uint32_t bytes : kPayloadSizes) {
      const json& d = sizes.at(std::to_string(bytes));  // byte counts as strings
      for (const char* key : {"p50_us", "p90_us", "p99_us", "p999_us", "max_us", "samples"})
        EXPECT_TRUE(d.at(key).is_number()) << name << " " << bytes << " " << key;
      EXPECT_EQ(d.size(), 6u);
      EXPECT_EQ(d.at("samples"), 100);
    }
  }
  const json& dds_1k = transports.at("dds").at("1024");
  EXPECT_DOUBLE_EQ(dds_1k.at("p50_us").get<double>(), 500.0);
  EXPECT_DOUBLE_EQ(dds_1k.at("p90_us").get<double>(), 900.0);
  EXPECT_DOUBLE_EQ(dds_1k.at("max_us").get<double>(), 1000.0);
  EXPECT_EQ(document.at("round_trip").at("afhub").at("64").at("samples"), 50);

  const json& jitter = document.at("loop_jitter");
  for (const char* who : {"afhub_us", "cyclictest_us"})
    for (const char* key : {"p50", "p99", "p999", "max"})
      EXPECT_TRUE(jitter.at(who).at(key).is_number()) << who << " " << key;
  // The highest value of the bin holding 20.5 us (20 480 to 20 607 ns).
  EXPECT_DOUBLE_EQ(jitter.at("afhub_us").at("p50").get<double>(), 20.607);
  EXPECT_DOUBLE_EQ(jitter.at("afhub_us").at("p99").get<double>(), 20.607);
  EXPECT_DOUBLE_EQ(jitter.at("afhub_us").at("max").get<double>(), 70.5);
  EXPECT_DOUBLE_EQ(jitter.at("cyclictest_us").at("max").get<double>(), 30.0);
  EXPECT_DOUBLE_EQ(document.at("loop_deadline_hit_ratio").get<double>(), 0.9995);
}

TEST(BenchReport, JsonSaysNullForALoopThatDidNotRun) {
  BenchResults results = known_results();
  results.loop.skipped = "--loop-seconds 0";
  const json document = test::parse_json(results_json(results));
  EXPECT_TRUE(document.at("loop_jitter").at("afhub_us").is_null());
  EXPECT_TRUE(document.at("loop_deadline_hit_ratio").is_null());
  EXPECT_EQ(document.at("skipped").at("loop"), "--loop-seconds 0");
}

TEST(BenchReport, TableGivesRatiosToAfhubAndTheGoalsVerdicts) {
  const std::string table = results_table(known_results());
  EXPECT_TRUE(contains(table, "(10.0x)")) << table;  // dds is 10x afhub at every size
  EXPECT_TRUE(contains(table, "(1.2x)")) << table;
  EXPECT_TRUE(contains(table, "ros1    skipped: not built")) << table;
  EXPECT_TRUE(contains(table, "vs dds 500.00 us: 10.0x lower (goal 3.0x): met")) << table;
  EXPECT_TRUE(contains(table, "vs uds 60.00 us: 1.2x lower (goal 1.5x): NOT met")) << table;
  EXPECT_TRUE(contains(table, "1 MiB is 1.00x its median at 1 KiB (goal <= 2): met")) << table;
  EXPECT_TRUE(contains(table, "99.95 % of 20000 steps")) << table;
  EXPECT_FALSE(contains(table, "late by the physics' step log")) << table;  // none was late
  // The loop's p99 is 20.6 us against cyclictest's 19.1 (bins' highest values): within 2x.
  EXPECT_TRUE(contains(table, "loop p99 wake-up 21 us vs cyclictest 19 us: 1.08x (goal <= 2): met"))
      << table;
}

// The late commands told apart, from the physics' step log.
TEST(BenchReport, TableSaysWhichLateCommandsCameWithThePhysicsBehind) {
  BenchResults results = known_results();
  results.loop.late = {10, 7, 3, 2, 19'900};
  const std::string table = results_table(results);
  EXPECT_TRUE(contains(table,
                       "10 late by the physics' step log: 7 at a step it began over 0.3 ms behind "
                       "its grid, or the step after (it fell behind 3 times, 2 of them waking up "
                       "late: the machine held it); at the other 19900 steps, 99.98 % in time"))
      << table;
}

// The slot against the bare floor of the same run: only when both move every byte
// (--touch); without it the floor moves one cache line and the slot the whole payload.
TEST(BenchReport, TheSlotIsSetAgainstTheFloorOnlyWhenEveryByteMoves) {
  BenchResults results = known_results();
  results.transports.push_back(transport("afhub-slot", 0.01));  // 0.50 us at the median
  results.transports.push_back(transport("shm-floor", 0.007));  // 0.35 us
  results.options.touch = true;
  std::string table = results_table(results);
  EXPECT_TRUE(contains(table,
                       "afhub-slot against shm-floor (bare shared memory, the machine's floor, "
                       "0.35 us / 0.69 us): median 1.43x, p99 1.43x the floor\n"))
      << table;
  results.transports.back() = transport("shm-floor", 0.01 * 0.9);  // 0.45 us
  table = results_table(results);
  EXPECT_TRUE(contains(table, "the floor; the 0.4 us goal is below it on this machine")) << table;
  results.options.touch = false;
  table = results_table(results);
  EXPECT_FALSE(contains(table, "against shm-floor")) << table;
}

// The plot's wake-up histogram: at cyclictest's resolution (whole microseconds) below
// 128 us, its counts are in consecutive rows; finer, 16 and 17 us had eight empty bins
// between them, and the curve of a log scale vanished.
TEST(BenchReport, TheLoopsHistogramIsDrawnAtWholeMicrosecondsBelow128) {
  LatencyHistogram h;
  h.record(16'000, 500);
  h.record(17'000, 300);
  h.record(200'000, 1);
  const auto rows = histogram_rows(h);
  std::map<double, std::uint64_t> by_edge(rows.begin(), rows.end());
  EXPECT_EQ(by_edge.size(), rows.size()) << "an edge twice";
  EXPECT_EQ(by_edge.at(17.0), 500u);  // 16.000 us falls in (16, 17]
  EXPECT_EQ(by_edge.at(18.0), 300u);
  for (const auto& [edge, count] : rows) {
    if (edge < 128.0) {
      EXPECT_EQ(edge, std::floor(edge)) << "not a whole microsecond";
    }
    if (edge > 18.0 && edge < 128.0) {
      EXPECT_EQ(count, 0u) << edge;
    }
  }
  std::uint64_t total = 0;
  for (const auto& row : rows) total += row.second;
  EXPECT_EQ(total, 801u);
  EXPECT_GT(rows.back().first, 200.0);  // the last row holds the maximum
}

}  // namespace
}  // namespace afhub::bench
