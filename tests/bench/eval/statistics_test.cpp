// Error statistics against hand-computed values (evo / numpy definitions).
#include <cmath>

#include <gtest/gtest.h>

#include "bench/eval/statistics.hpp"

namespace rotolidar::bench {
namespace {

TEST(Statistics, HandComputedVector) {
  // e = {3, 1, 4, 1, 5, 9}: sum 23, mean 23/6, sse 9+1+16+1+25+81 = 133, sorted 1 1 3 4 5 9 -> median 3.5,
  // population variance = 133/6 - (23/6)^2 = (798 - 529)/36 = 269/36.
  const ErrorStatistics s = ComputeStatistics({3, 1, 4, 1, 5, 9});
  EXPECT_EQ(s.count, 6u);
  EXPECT_DOUBLE_EQ(s.max, 9.0);
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.mean, 23.0 / 6.0);
  EXPECT_DOUBLE_EQ(s.median, 3.5);
  EXPECT_DOUBLE_EQ(s.sse, 133.0);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(133.0 / 6.0));
  EXPECT_NEAR(s.std, std::sqrt(269.0 / 36.0), 1e-15);
}

TEST(Statistics, OddCountMedianAndSingleValue) {
  EXPECT_DOUBLE_EQ(ComputeStatistics({5, 2, 7}).median, 5.0);
  const ErrorStatistics s = ComputeStatistics({2.5});
  EXPECT_DOUBLE_EQ(s.rmse, 2.5);
  EXPECT_DOUBLE_EQ(s.std, 0.0);
}

TEST(Statistics, EmptyIsNan) {
  const ErrorStatistics s = ComputeStatistics({});
  EXPECT_EQ(s.count, 0u);
  EXPECT_TRUE(std::isnan(s.rmse));
  EXPECT_TRUE(std::isnan(s.median));
}

}  // namespace
}  // namespace rotolidar::bench
