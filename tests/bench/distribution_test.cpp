// The bench's statistics: exact nearest-rank percentiles from samples, and the
// same summary read from a 1 us histogram.
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

TEST(Distribution, NearestRankRoundsUpBetweenSamples) {
  const std::vector<double> sorted = {1.5, 2.5, 3.5};
  EXPECT_DOUBLE_EQ(nearest_rank(sorted, 0.5), 2.5);    // rank ceil(1.5) = 2
  EXPECT_DOUBLE_EQ(nearest_rank(sorted, 0.34), 2.5);   // rank ceil(1.02) = 2
  EXPECT_DOUBLE_EQ(nearest_rank(sorted, 0.33), 1.5);   // rank ceil(0.99) = 1
  EXPECT_DOUBLE_EQ(nearest_rank(sorted, 0.999), 3.5);  // the tail is the maximum
  EXPECT_DOUBLE_EQ(nearest_rank({4.0}, 0.5), 4.0);
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

TEST(Distribution, FromAHistogramPercentilesAreBinUpperEdges) {
  LatencyHistogram histogram;
  for (int i = 0; i < 800; ++i) histogram.record(20.3);  // bin [20, 21)
  for (int i = 0; i < 190; ++i) histogram.record(35.0);
  for (int i = 0; i < 10; ++i) histogram.record(812.5);
  const Distribution d = summarize(histogram);
  EXPECT_EQ(d.samples, 1000u);
  EXPECT_DOUBLE_EQ(d.p50_us, 21.0);
  EXPECT_DOUBLE_EQ(d.p90_us, 36.0);
  EXPECT_DOUBLE_EQ(d.p99_us, 36.0);
  EXPECT_DOUBLE_EQ(d.p999_us, 812.5);  // capped at the exact maximum
  EXPECT_DOUBLE_EQ(d.max_us, 812.5);
}

}  // namespace
}  // namespace afhub::bench
