#include "sim/rig/motor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace rotolidar::sim {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;

/// (true - decoded) angle in counts, wrapped to [-cpr/2, cpr/2]; decoded the way a reader does (RigCalib).
double ErrorCounts(const EncoderConfig& c, double theta_true, uint32_t count) {
  RigCalib calib;
  calib.encoder = c.ToCalib();
  const double e = std::remainder(theta_true - calib.EncoderAngle(count), kTwoPi);
  return e / kTwoPi * c.counts_per_rev;
}

TEST(ConstantSpeedRotor, AngleIsLinearInTime) {
  const ConstantSpeedRotor rotor(MotorConfig{2.6, 0.3});
  EXPECT_DOUBLE_EQ(rotor.AngleAt(0.0), 0.3);
  EXPECT_DOUBLE_EQ(rotor.AngleAt(10.0), 0.3 + 26.0);
  EXPECT_DOUBLE_EQ(rotor.SpeedAt(5.0), 2.6);
  std::string error;
  EXPECT_FALSE((MotorConfig{std::nan(""), 0.0}.Validate(&error)));
  EXPECT_NE(error.find("speed_radps"), std::string::npos) << error;
}

TEST(EncoderConfig, PresetsAndValidation) {
  EXPECT_EQ(EncoderConfig::Bits12().counts_per_rev, 4096u);
  EXPECT_EQ(EncoderConfig::Bits14().counts_per_rev, 16384u);
  std::string error;
  EncoderConfig c;
  EXPECT_TRUE(c.Validate(&error)) << error;
  c.latency_s = -1e-3;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("latency_s"), std::string::npos) << error;
  c = {};
  c.counts_per_rev = 3;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("counts_per_rev"), std::string::npos) << error;
}

// Without noise, floor quantisation and the bin-centre decoding (RigCalib::EncoderAngle) put the decoded angle
// within half a count of the true angle at (t - latency): the error in counts lies in [-0.5, 0.5). Checked for
// both presets, a zero offset, latency and both spin directions, over many turns (unwrapped angles up to ~500 rad).
TEST(EncoderModel, NoiseFreeErrorIsWithinHalfACount) {
  for (uint32_t cpr : {4096u, 16384u}) {
    for (double speed : {2.6, -7.0}) {
      EncoderConfig c;
      c.counts_per_rev = cpr;
      c.noise_sigma_counts = 0.0;
      c.latency_s = 2e-3;
      c.zero_offset_rad = 0.7;
      const ConstantSpeedRotor rotor(MotorConfig{speed, 1.0});
      EncoderModel enc(c, 42);
      const auto samples = enc.SampleRange(rotor, 0.0, 70.0);
      ASSERT_EQ(samples.size(), 70001u);
      for (const EncoderSample& s : samples) {
        ASSERT_LT(s.count, cpr);
        const double e = ErrorCounts(c, rotor.AngleAt(s.t_s - c.latency_s), s.count);
        ASSERT_GE(e, -0.5 - 1e-6) << "t " << s.t_s;  // 1e-6 counts: double rounding of ~500 rad angles
        ASSERT_LT(e, 0.5 + 1e-6) << "t " << s.t_s;
      }
    }
  }
}

// With Gaussian noise sigma (counts) added before the floor, the error is U[-0.5,0.5) - sigma*N: it stays inside
// [-0.5 - 5 sigma, 0.5 + 5 sigma] (5 sigma: P ~ 6e-7 per sample, 1e5 samples), its mean is 0 (bin-centre
// decoding removes the floor's half-count bias) and its variance is 1/12 + sigma^2. Mean standard error: sqrt((1/12 + 0.25) / 1e5) = 1.8e-3 -> bound 4x = 0.008.
TEST(EncoderModel, NoisyErrorMatchesQuantisationPlusNoise) {
  EncoderConfig c;
  c.noise_sigma_counts = 0.5;
  const ConstantSpeedRotor rotor(MotorConfig{2.6, 0.0});
  EncoderModel enc(c, 7);
  const auto samples = enc.SampleRange(rotor, 0.0, 99.999);
  double sum = 0, sum2 = 0;
  for (const EncoderSample& s : samples) {
    const double e = ErrorCounts(c, rotor.AngleAt(s.t_s), s.count);
    ASSERT_GE(e, -0.5 - 5 * c.noise_sigma_counts);
    ASSERT_LT(e, 0.5 + 5 * c.noise_sigma_counts);
    sum += e, sum2 += e * e;
  }
  const double n = static_cast<double>(samples.size());
  const double mean = sum / n, var = sum2 / n - mean * mean;
  std::printf("encoder error mean %.4g counts, variance %.4g (expected 0, %.4g)\n", mean, var, 1.0 / 12 + 0.25);
  EXPECT_NEAR(mean, 0.0, 0.008);
  EXPECT_NEAR(var, 1.0 / 12.0 + 0.25, 0.02);  // var of var estimate ~ 2 var^2 / n -> sd 1.5e-3
}

TEST(EncoderModel, QuantiseWrapsIntoOneTurn) {
  EncoderConfig c;
  c.noise_sigma_counts = 0.0;
  const EncoderModel enc(c, 1);
  EXPECT_EQ(enc.Quantise(0.0, 0.0), 0u);
  EXPECT_EQ(enc.Quantise(-1e-9, 0.0), 4095u);
  EXPECT_EQ(enc.Quantise(-1e-20, 0.0), 0u);  // rounds to a full turn, wraps to 0
  EXPECT_EQ(enc.Quantise(kTwoPi - 1e-9, 0.0), 4095u);
  EXPECT_EQ(enc.Quantise(kTwoPi - 1e-9, 2.0), 1u);  // noise pushes past the wrap
  EXPECT_EQ(enc.Quantise(0.0, -0.5), 4095u);
  EXPECT_EQ(enc.Quantise(1000.0 * kTwoPi + M_PI + 1e-6, 0.0), 2048u);  // half a turn after 1000 turns
}

TEST(EncoderModel, SameSeedSameSamplesDifferentSeedDifferent) {
  EncoderConfig c;
  c.noise_sigma_counts = 1.0;
  const ConstantSpeedRotor rotor(MotorConfig{});
  EncoderModel a(c, 123), b(c, 123), d(c, 124);
  const auto sa = a.SampleRange(rotor, 0.0, 1.0), sb = b.SampleRange(rotor, 0.0, 1.0),
             sd = d.SampleRange(rotor, 0.0, 1.0);
  int differ = 0;
  for (size_t i = 0; i < sa.size(); ++i) {
    EXPECT_EQ(sa[i].count, sb[i].count);
    EXPECT_EQ(sa[i].t_s, sb[i].t_s);
    differ += sa[i].count != sd[i].count;
  }
  EXPECT_GT(differ, static_cast<int>(sa.size()) / 4);
}

}  // namespace
}  // namespace rotolidar::sim
