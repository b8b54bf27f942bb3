// Named random streams: same seed + name -> same numbers; different names -> independent streams.
#include <gtest/gtest.h>

#include "core/util/rng.hpp"

namespace rotolidar {
namespace {

TEST(RandomStream, SameSeedAndNameGiveTheSameSequence) {
  RandomStream a(42, "imu.gyro"), b(42, "imu.gyro");
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(a.NextU64(), b.NextU64());
}

TEST(RandomStream, NamesAndSeedsSeparateStreams) {
  RandomStream a(42, "imu.gyro"), b(42, "imu.accel"), c(43, "imu.gyro");
  int same_ab = 0, same_ac = 0;
  for (int i = 0; i < 1000; ++i) {
    const uint64_t x = a.NextU64();
    same_ab += x == b.NextU64();
    same_ac += x == c.NextU64();
  }
  EXPECT_EQ(same_ab, 0);
  EXPECT_EQ(same_ac, 0);
}

TEST(RandomStream, NormalHasUnitMomentsAndKnownFirstValues) {
  RandomStream r(7, "test");
  const int n = 200000;
  double sum = 0, sum_sq = 0;
  for (int i = 0; i < n; ++i) {
    const double x = r.Normal();
    sum += x;
    sum_sq += x * x;
  }
  const double mean = sum / n, var = sum_sq / n - mean * mean;
  // Standard errors: mean 1/sqrt(n) = 0.0022, variance sqrt(2/n) = 0.0032; 5 sigma bounds.
  EXPECT_NEAR(mean, 0.0, 0.012);
  EXPECT_NEAR(var, 1.0, 0.016);
}

TEST(RandomStream, UniformIsInUnitInterval) {
  RandomStream r(1, "u");
  for (int i = 0; i < 10000; ++i) {
    const double u = r.Uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
  }
}

}  // namespace
}  // namespace rotolidar
