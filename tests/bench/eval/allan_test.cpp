#include "bench/eval/allan.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/util/rng.hpp"
#include "sim/sensors/imu_model.hpp"

namespace rotolidar::bench {
namespace {

/// y_k = b_k + N sqrt(rate) w_k,  b_k = b_(k-1) + K sqrt(1 / rate) r_k: Kalibr's discrete model of one axis.
std::vector<double> WhitePlusWalk(double N, double K, double rate_hz, long n, uint64_t seed) {
  RandomStream white(seed, "test.white"), walk(seed, "test.walk");
  std::vector<double> y(static_cast<size_t>(n));
  double b = 0.0;
  for (long i = 0; i < n; ++i) {
    b += K * std::sqrt(1.0 / rate_hz) * walk.Normal();
    y[size_t(i)] = 3.0 + b + N * std::sqrt(rate_hz) * white.Normal();  // a constant offset must not matter
  }
  return y;
}

// White noise only: AVAR(tau) = N^2 / tau exactly in expectation. At 100 Hz over 2000 s the m = 1..100 points
// have relative AVAR errors of ~1-10 % (ADEV half that); bound 10 % on ADEV. The fit pins N with all the
// short-tau points: over 40 seeds the error was < 0.5 % (N) -> bound 2 %; the spurious K stays below the
// level at which it would change AVAR by 10 % at the largest tau (K^2 tau_max / 3 < 0.1 N^2 / tau_max).
TEST(Allan, WhiteNoiseGivesTheDensity) {
  const double N = 0.02, rate = 100.0;
  const std::vector<double> y = WhitePlusWalk(N, 0.0, rate, 200000, 11);
  const AllanCurve curve = OverlappingAllanDeviation(y, rate);
  ASSERT_GT(curve.tau_s.size(), 40u);
  EXPECT_EQ(curve.cluster_size.front(), 1);
  EXPECT_LE(curve.tau_s.back(), 0.1 * 2000.0 + 1e-9);
  for (size_t i = 1; i < curve.tau_s.size(); ++i) EXPECT_GT(curve.tau_s[i], curve.tau_s[i - 1]);
  for (size_t i = 0; i < curve.tau_s.size() && curve.cluster_size[i] <= 100; ++i)
    EXPECT_NEAR(curve.adev[i], N / std::sqrt(curve.tau_s[i]), 0.1 * N / std::sqrt(curve.tau_s[i]))
        << "tau " << curve.tau_s[i];
  const AllanFit fit = FitAllan(curve);
  ASSERT_TRUE(fit.converged);
  std::printf("white: N %.5g (true %.5g), K %.3g, rms log residual %.3f\n", fit.white_density, N, fit.random_walk,
              fit.rms_log_residual);
  EXPECT_NEAR(fit.white_density, N, 0.02 * N);
  const double tau_max = curve.tau_s.back();
  EXPECT_LT(fit.random_walk * fit.random_walk * tau_max / 3.0, 0.1 * N * N / tau_max);
}

// White + random walk, tau_c = sqrt(3) N / K = 1.7 s, record T = 6000 s = 3500 tau_c. Measured over 40 seeds
// (/tmp experiment, same fit): |K error| median 1.3 %, 90th percentile 3.8 %, max 5.3 % at T = 3300 tau_c;
// N error < 0.3 %. Bounds: K 10 % (the brief's target), N 2 %.
TEST(Allan, WhitePlusRandomWalkGivesBothTerms) {
  const double N = 1e-3, K = 1e-3, rate = 100.0;
  for (uint64_t seed : {1u, 2u}) {
    const AllanCurve curve = OverlappingAllanDeviation(WhitePlusWalk(N, K, rate, 600000, seed), rate);
    const AllanFit fit = FitAllan(curve);
    ASSERT_TRUE(fit.converged);
    std::printf("seed %lu: N %.5g (true %.3g), K %.5g (true %.3g), rms log residual %.3f, %d points\n",
                static_cast<unsigned long>(seed), fit.white_density, N, fit.random_walk, K, fit.rms_log_residual,
                fit.points);
    EXPECT_NEAR(fit.white_density, N, 0.02 * N);
    EXPECT_NEAR(fit.random_walk, K, 0.10 * K);
    EXPECT_LT(fit.rms_log_residual, 0.2);
  }
}

// With the optional flat term, a pure white + walk record gives a small B (its AVAR share at tau_c stays below
// a quarter of the model there) and the same N and K.
TEST(Allan, BiasInstabilityTermIsOptional) {
  const double N = 1e-3, K = 1e-3, rate = 100.0;
  AllanOptions options;
  options.fit_bias_instability = true;
  const AllanCurve curve = OverlappingAllanDeviation(WhitePlusWalk(N, K, rate, 600000, 3), rate, options);
  const AllanFit fit = FitAllan(curve, options);
  ASSERT_TRUE(fit.converged);
  std::printf("with B: N %.4g K %.4g B %.3g\n", fit.white_density, fit.random_walk, fit.bias_instability);
  EXPECT_NEAR(fit.white_density, N, 0.03 * N);
  EXPECT_NEAR(fit.random_walk, K, 0.15 * K);
  const double tau_c = std::sqrt(3.0) * N / K;
  EXPECT_LT(2.0 * std::log(2.0) / M_PI * fit.bias_instability * fit.bias_instability, 0.25 * 2.0 * N * N / tau_c);
}

TEST(Allan, ShortSeriesGiveNoFit) {
  EXPECT_TRUE(OverlappingAllanDeviation({1.0, 2.0, 3.0}, 10.0).tau_s.empty());
  EXPECT_FALSE(FitAllan(OverlappingAllanDeviation({1.0, 2.0, 3.0, 4.0, 5.0}, 10.0)).converged);
}

// A static BMI055 (sim::ImuModel, Bmi055Noise) recovers its configured densities and walks on all six axes.
// Allan's N and K do not depend on the sample rate, so the model runs at 1 Hz to cover T = 133 h cheaply
// (480k samples): that is 3000 tau_c for the gyro (tau_c = sqrt(3) N / K = 159 s) and 22000 tau_c for the
// accelerometer (22 s). Measured (40 seeds, /tmp experiment at these parameters): K errors at 3000 tau_c have a
// 90th percentile of ~4 % and a max of ~6 %; N < 0.5 %. Bounds: K 10 %, N 3 % (the lowest tau of 1 s is
// still in the white regime for both sensors).
TEST(Allan, StaticImuModelRecoversTheConfiguredNoise) {
  ImuNoise noise = sim::Bmi055Noise();
  noise.rate_hz = 1.0;
  sim::ImuModel imu(noise, Pose3::Identity(), 2024);
  const long n = long(133.0 * 3600.0 * noise.rate_hz);
  std::vector<ImuSample> samples;
  samples.reserve(size_t(n));
  for (long i = 0; i < n; ++i) samples.push_back(imu.Sample(sim::BaseKinematics{}, double(i) / noise.rate_hz));
  const AllanReport report = FitImuAllan(samples, noise.rate_hz);
  EXPECT_NEAR(report.duration_s, 133.0 * 3600.0, 1.0);
  for (int a = 0; a < 3; ++a) {
    const AllanFit& g = report.gyro[size_t(a)].fit;
    const AllanFit& f = report.accel[size_t(a)].fit;
    std::printf("axis %d: gyro N %.4g/%.4g K %.4g/%.4g | accel N %.4g/%.4g K %.4g/%.4g\n", a, g.white_density,
                noise.gyro_noise_density, g.random_walk, noise.gyro_random_walk, f.white_density,
                noise.accel_noise_density, f.random_walk, noise.accel_random_walk);
    EXPECT_NEAR(g.white_density, noise.gyro_noise_density, 0.03 * noise.gyro_noise_density);
    EXPECT_NEAR(g.random_walk, noise.gyro_random_walk, 0.10 * noise.gyro_random_walk);
    EXPECT_NEAR(f.white_density, noise.accel_noise_density, 0.03 * noise.accel_noise_density);
    EXPECT_NEAR(f.random_walk, noise.accel_random_walk, 0.10 * noise.accel_random_walk);
  }
  std::ostringstream csv;
  WriteAllanTable(csv, report);
  EXPECT_EQ(csv.str().rfind("tau_s,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z\n", 0), 0u);
  EXPECT_NE(csv.str().find("# fit accel_z: noise_density"), std::string::npos);
}

}  // namespace
}  // namespace rotolidar::bench
