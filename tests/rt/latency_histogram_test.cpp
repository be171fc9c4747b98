// afhub's percentile rule (nearest rank) on small cases worked by hand, and the
// log-linear histogram against it: exact below 256 ns, never below the exact
// percentile and less than 1/128 above it over ns to tens of seconds, its edges
// (zero, negative, overflow, empty), its size, and no allocation when recording or
// reading.
#include "afhub/rt/latency_histogram.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "afhub/rt/loop_timing.hpp"
#include "afhub/rt/percentile.hpp"
#include "heap_counter.hpp"

namespace afhub {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Every q the loops, the bench, teleop and the bridge report, and some between.
const std::vector<double> kQuantiles = {0.001, 0.01, 0.1,   0.25,   0.5,     0.75,
                                        0.9,   0.99, 0.999, 0.9999, 0.99999, 1.0};

TEST(PercentileRule, RanksOfSmallCases) {
  EXPECT_EQ(percentile_rank(4, 0.5), 2u);  // {1, 2, 3, 4}: p50 is 2, not 2.5 nor 3
  EXPECT_EQ(percentile_rank(4, 0.25), 1u);
  EXPECT_EQ(percentile_rank(4, 0.26), 2u);  // ceil(1.04)
  EXPECT_EQ(percentile_rank(4, 0.75), 3u);
  EXPECT_EQ(percentile_rank(4, 1.0), 4u);
  EXPECT_EQ(percentile_rank(3, 0.34), 2u);  // ceil(1.02)
  EXPECT_EQ(percentile_rank(3, 0.33), 1u);  // ceil(0.99)
  EXPECT_EQ(percentile_rank(100, 0.99), 99u);
  EXPECT_EQ(percentile_rank(1000, 0.999), 999u);
  EXPECT_EQ(percentile_rank(1001, 0.999), 1000u);  // ceil(999.999)
  EXPECT_EQ(percentile_rank(10, 0.7), 7u);         // 0.7 * 10 is 7.000000000000001 in doubles
  EXPECT_EQ(percentile_rank(1, 0.5), 1u);
  EXPECT_EQ(percentile_rank(1'000'000'000, 0.99), 990'000'000u);
}

TEST(PercentileRule, OutOfRangeQuantilesReadTheEnds) {
  EXPECT_EQ(percentile_rank(0, 0.5), 0u);  // nothing to read
  EXPECT_EQ(percentile_rank(10, 0.0), 1u);
  EXPECT_EQ(percentile_rank(10, -3.0), 1u);
  EXPECT_EQ(percentile_rank(10, 2.0), 10u);
  EXPECT_EQ(percentile_rank(10, kNaN), 10u);
  EXPECT_EQ(percentile_rank(10, std::numeric_limits<double>::infinity()), 10u);
}

TEST(PercentileRule, OfSortedSamples) {
  const std::vector<double> sorted = {1.5, 2.5, 3.5};
  EXPECT_DOUBLE_EQ(percentile_of_sorted<double>(sorted, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(percentile_of_sorted<double>(sorted, 0.33), 1.5);
  EXPECT_DOUBLE_EQ(percentile_of_sorted<double>(sorted, 0.999), 3.5);  // the tail is the max
  const std::vector<std::int64_t> none;
  EXPECT_EQ(percentile_of_sorted<std::int64_t>(none, 0.5), 0);
}

// Below 256 ns a bin is 1 ns: the histogram's percentiles are the exact ones.
TEST(LatencyHistogram, ExactBelow256Ns) {
  std::mt19937_64 random(1);
  std::uniform_int_distribution<std::int64_t> ns(0, 255);
  LatencyHistogram histogram;
  std::vector<std::int64_t> samples;
  for (int i = 0; i < 5000; ++i) {
    samples.push_back(ns(random));
    histogram.record(samples.back());
  }
  std::sort(samples.begin(), samples.end());
  for (const double q : kQuantiles)
    EXPECT_EQ(histogram.percentile_ns(q), percentile_of_sorted<std::int64_t>(samples, q)) << q;
}

// The bins tile 0 to kLimitNs without gap or overlap, each at most 1/128 of its
// lowest value wide (above the 1 ns bins).
TEST(LatencyHistogram, BinsTileTheRange) {
  EXPECT_EQ(LatencyHistogram::lowest_ns(0), 0);
  for (std::size_t bin = 0; bin < LatencyHistogram::kBins; ++bin) {
    const std::int64_t low = LatencyHistogram::lowest_ns(bin);
    const std::int64_t high = LatencyHistogram::highest_ns(bin);
    ASSERT_EQ(LatencyHistogram::bin_of(low), bin);
    ASSERT_EQ(LatencyHistogram::bin_of(high), bin);
    ASSERT_LE((high - low + 1) * LatencyHistogram::kSubBins, std::max<std::int64_t>(low, 128))
        << bin;
    if (bin + 1 < LatencyHistogram::kBins) {
      ASSERT_EQ(LatencyHistogram::lowest_ns(bin + 1), high + 1) << bin;
    }
  }
  EXPECT_EQ(LatencyHistogram::highest_ns(LatencyHistogram::kBins - 1) + 1,
            LatencyHistogram::kLimitNs);
}

// Samples spread over 1 ns to 60 s on a log scale, with a pile in the microseconds
// as a loop's would be: every percentile the histogram reads is the bin of the
// exact one (same rule), so it is never below and less than 1/128 above.
TEST(LatencyHistogram, WithinOnePercentOfTheExactPercentiles) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> exponent(0.0, std::log(60e9));
  std::lognormal_distribution<double> loop(std::log(20'000.0), 0.5);
  double worst = 0.0;
  for (int round = 0; round < 20; ++round) {
    LatencyHistogram histogram;
    std::vector<std::int64_t> samples;
    const int n = 1000 + round * 5000;
    for (int i = 0; i < n; ++i) {
      const double ns = i % 3 == 0 ? std::exp(exponent(random)) : loop(random);
      samples.push_back(static_cast<std::int64_t>(ns));
      histogram.record(samples.back());
    }
    std::sort(samples.begin(), samples.end());
    EXPECT_EQ(histogram.count(), samples.size());
    EXPECT_EQ(histogram.max_ns(), samples.back());
    for (const double q : kQuantiles) {
      const std::int64_t exact = percentile_of_sorted<std::int64_t>(samples, q);
      const std::int64_t read = histogram.percentile_ns(q);
      ASSERT_GE(read, exact) << q;
      const double error = static_cast<double>(read - exact) / static_cast<double>(exact);
      ASSERT_LT(error, 1.0 / 128) << q << ": exact " << exact << " ns, read " << read << " ns";
      worst = std::max(worst, error);
    }
  }
  std::printf("largest relative error of a percentile: %.4f %% (bound %.4f %%)\n", worst * 100,
              100.0 / 128);
}

TEST(LatencyHistogram, EmptyReadsZero) {
  const LatencyHistogram histogram;
  EXPECT_EQ(histogram.count(), 0u);
  EXPECT_EQ(histogram.percentile_ns(0.5), 0);
  EXPECT_EQ(histogram.percentile_ns(1.0), 0);
  EXPECT_EQ(histogram.max_ns(), 0);
}

TEST(LatencyHistogram, NegativeDurationsCountAsZero) {
  LatencyHistogram histogram;
  histogram.record(-5);
  histogram.record(std::numeric_limits<std::int64_t>::min());
  histogram.record(0);
  histogram.record(1000);
  EXPECT_EQ(histogram.count(), 4u);
  EXPECT_EQ(histogram.bin_count(0), 3u);
  EXPECT_EQ(histogram.percentile_ns(0.75), 0);
  EXPECT_EQ(histogram.percentile_ns(1.0), 1000);
}

TEST(LatencyHistogram, BeyondTheRangeCountsAsOverflowAndReadsTheMaximum) {
  LatencyHistogram histogram;
  histogram.record(10'000);
  histogram.record(LatencyHistogram::kLimitNs - 1);  // the last bin
  histogram.record(LatencyHistogram::kLimitNs);
  histogram.record(std::numeric_limits<std::int64_t>::max());
  EXPECT_EQ(histogram.count(), 4u);
  EXPECT_EQ(histogram.overflow(), 2u);
  EXPECT_EQ(histogram.percentile_ns(0.25),
            LatencyHistogram::highest_ns(LatencyHistogram::bin_of(10'000)));
  EXPECT_EQ(histogram.percentile_ns(0.5), LatencyHistogram::kLimitNs - 1);
  EXPECT_EQ(histogram.percentile_ns(0.75), std::numeric_limits<std::int64_t>::max());
  EXPECT_EQ(histogram.max_ns(), std::numeric_limits<std::int64_t>::max());
}

TEST(LatencyHistogram, APercentileIsNeverAboveTheMaximum) {
  LatencyHistogram histogram;
  histogram.record(1'000'001);  // its bin reaches 1 007 615 ns
  EXPECT_EQ(histogram.percentile_ns(0.5), 1'000'001);
  EXPECT_DOUBLE_EQ(histogram.percentile_us(0.5), 1000.001);
}

TEST(LatencyHistogram, RecordingTimesOverIsRecordingEachTime) {
  LatencyHistogram once, each;
  once.record(123'456, 1000);
  for (int i = 0; i < 1000; ++i) each.record(123'456);
  EXPECT_EQ(once.count(), each.count());
  EXPECT_EQ(once.percentile_ns(0.5), each.percentile_ns(0.5));
  once.record(7'000, 0);  // no sample, and no maximum below it
  EXPECT_EQ(once.count(), 1000u);
  EXPECT_EQ(once.max_ns(), 123'456);
}

// A loop's two histograms held 1.6 MB in 1 us bins up to 100 ms; these hold the
// whole range in a few tens of kilobytes, in the object itself.
TEST(LatencyHistogram, IsSmallAndFixed) {
  EXPECT_LE(sizeof(LatencyHistogram), 32u * 1024);
  EXPECT_LE(sizeof(LoopTiming), 64u * 1024);
  std::printf("LatencyHistogram %zu bytes, LoopTiming %zu bytes\n", sizeof(LatencyHistogram),
              sizeof(LoopTiming));
}

TEST(LatencyHistogram, RecordingAndReadingAllocateNothing) {
  LoopTiming timing;
  LatencyHistogram histogram;
  LoopStats stats;
  std::int64_t sink = 0;
  const long before = test::heap_allocations();
  for (std::int64_t i = 0; i < 100'000; ++i) {
    histogram.record((i * 7919) % 2'000'000'000 - 10);
    timing.record(i * 13, i * 1013);
  }
  histogram.record(2 * LatencyHistogram::kLimitNs);  // an overflow
  for (const double q : kQuantiles) sink += histogram.percentile_ns(q);
  timing.fill(stats);
  EXPECT_EQ(test::heap_allocations(), before);
  EXPECT_GT(sink, 0);
  EXPECT_EQ(stats.cycles, 100'000u);
}

}  // namespace
}  // namespace afhub
