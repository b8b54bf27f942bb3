#include "sim/rig/motor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "core/util/log.hpp"
#include "sim/rig/motor_profile.hpp"

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
      const ProfileRotor rotor(ConstantProfile(speed, 1.0));
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
  const ProfileRotor rotor(ConstantProfile(2.6, 0.0));
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
  const ProfileRotor rotor(ConstantProfile(2.6));
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

// The streaming encoder fed with states of an analytic rotor (pushed every 2 ms, so samples fall between states)
// reproduces EncoderModel on the same rotor exactly: same grid, same latency handling (cubic Hermite is exact on a
// linear angle up to rounding, ~1e-14 rad here, so a floor could only differ within 1e-11 counts of a bin edge:
// P ~ 1e-6 over these samples), same noise stream.
TEST(EncoderStream, MatchesEncoderModelOnTheSameRotor) {
  EncoderConfig c = EncoderConfig::Bits14();
  c.noise_sigma_counts = 0.8;
  c.latency_s = 3.3e-3;
  c.zero_offset_rad = 0.9;
  const ProfileRotor rotor(ConstantProfile(-4.1, 2.0));
  EncoderModel model(c, 99);
  EncoderStream stream(c, 99);
  std::vector<EncoderSample> streamed;
  for (int k = 0; k <= 10000; ++k) {
    const double t = k * 2e-3;
    stream.Push({t, rotor.AngleAt(t), rotor.SpeedAt(t)}, &streamed);
  }
  const auto expected = model.SampleRange(rotor, 0.0, 20.0);
  ASSERT_EQ(streamed.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(streamed[i].t_s, expected[i].t_s) << i;
    ASSERT_EQ(streamed[i].count, expected[i].count) << "t " << expected[i].t_s;
  }
}

// Hermite interpolation on (theta, omega) is exact for cubic motion; before the first state the stream extrapolates
// at the first state's speed. The first sample is the first grid time at or after the first state.
TEST(EncoderStream, InterpolatesTheHistoryAndStartsOnTheGrid) {
  EncoderConfig c;
  c.noise_sigma_counts = 0.0;
  c.latency_s = 5e-3;
  EncoderStream stream(c, 1);
  auto theta = [](double t) { return 0.5 + 2.0 * t - 3.0 * t * t + 1.5 * t * t * t; };
  auto omega = [](double t) { return 2.0 - 6.0 * t + 4.5 * t * t; };
  std::vector<EncoderSample> out;
  const double t0 = 0.0105;  // not on the 1 ms grid
  for (int k = 0; k < 40; ++k) {
    const double t = t0 + k * 1.7e-3;
    stream.Push({t, theta(t), omega(t)}, &out);
  }
  ASSERT_FALSE(out.empty());
  EXPECT_DOUBLE_EQ(out.front().t_s, 11 * 1e-3);
  // The stream keeps the states the coming samples need: the last latency_s + 1 ms.
  const double t_last = t0 + 39 * 1.7e-3;
  for (double t = t_last - 5e-3; t <= t_last; t += 1.3e-4) EXPECT_NEAR(stream.TrueAngleAt(t), theta(t), 1e-12);
  EncoderStream fresh(c, 1);
  std::vector<EncoderSample> none;
  fresh.Push({t0, theta(t0), omega(t0)}, &none);
  EXPECT_TRUE(none.empty());  // the first grid time after t0 is 11 ms
  EXPECT_NEAR(fresh.TrueAngleAt(0.0), theta(t0) - omega(t0) * t0, 1e-12);
  RotorJointState late{0.0, 0.0, 0.0};
  EXPECT_THROW(stream.Push(late, &out), InternalError);
}

}  // namespace
}  // namespace rotolidar::sim
