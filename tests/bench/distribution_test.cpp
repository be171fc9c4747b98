// The bench's statistics: exact nearest-rank percentiles from samples (the rule
// itself is tested in tests/rt/latency_histogram_test.cpp), and the same summary read
// from a histogram.
#include "afhub/bench/distribution.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace afhub::bench {
namespace {

TEST(Distribution, NearestRankOfOneToAThousand) {
  std::vector<double> samples;
  for (int i = 1000; i >= 1; --i) samples.push_back(i);  // unsorted on purpose
  std::shuffle(samples.begin(), samples.end(), std::mt19937(7));
  const Distribution d = summarize(samples);
  EXPECT_EQ(d.samples, 1000u);
  EXPECT_DOUBLE_EQ(d.p50_us, 500.0);
  EXPECT_DOUBLE_EQ(d.p90_us, 900.0);
  EXPECT_DOUBLE_EQ(d.p99_us, 990.0);
  EXPECT_DOUBLE_EQ(d.p999_us, 999.0);
  EXPECT_DOUBLE_EQ(d.max_us, 1000.0);
}

TEST(Distribution, OneOutlierShowsOnlyInTheTail) {
  std::vector<double> samples(999, 2.0);
  samples.push_back(5000.0);
  const Distribution d = summarize(samples);
  EXPECT_DOUBLE_EQ(d.p50_us, 2.0);
  EXPECT_DOUBLE_EQ(d.p99_us, 2.0);
  EXPECT_DOUBLE_EQ(d.p999_us, 2.0);  // rank 999 of 1000
  EXPECT_DOUBLE_EQ(d.max_us, 5000.0);
}

TEST(Distribution, EmptyIsAllZero) {
  const Distribution d = summarize(std::vector<double>{});
  EXPECT_EQ(d.samples, 0u);
  EXPECT_EQ(d.p50_us, 0.0);
  EXPECT_EQ(d.max_us, 0.0);
}

// From a histogram: each percentile is the highest value of the bin holding the
// exact one, so at most 1/128 above it, and never above the exact maximum.
TEST(Distribution, FromAHistogramPercentilesAreWithinItsResolution) {
  LatencyHistogram histogram;
  histogram.record(20'300, 800);
  histogram.record(35'000, 190);
  histogram.record(812'500, 10);
  const Distribution d = summarize(histogram);
  EXPECT_EQ(d.samples, 1000u);
  EXPECT_DOUBLE_EQ(d.p50_us, 20.351);  // the bin 20 224 to 20 351 ns
  EXPECT_DOUBLE_EQ(d.p90_us, 35.071);  // the bin 34 816 to 35 071 ns
  EXPECT_DOUBLE_EQ(d.p99_us, 35.071);
  EXPECT_DOUBLE_EQ(d.p999_us, 812.5);  // capped at the exact maximum
  EXPECT_DOUBLE_EQ(d.max_us, 812.5);
}

}  // namespace
}  // namespace afhub::bench
