#include "sim/sensors/imu_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include <yaml-cpp/yaml.h>


namespace rotolidar::sim {
namespace {

Pose3 TiltedImuMount() {
  // A realistic mount: 10-20 cm lever arm and a rotated chip.
  return MakePose(Eigen::Vector3d(0.12, -0.05, 0.20),
                  Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized())));
}

BaseKinematics StaticBase() {
  BaseKinematics k;
  k.T_world_base = MakePose(Eigen::Vector3d(1, 2, 1.2),
                            Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, -1, 0.5).normalized())));
  return k;
}

TEST(ImuModel, StaticTrueSampleIsGravityUpInImuFrame) {
  const Pose3 T_base_imu = TiltedImuMount();
  const BaseKinematics k = StaticBase();
  const ImuModel imu(ImuNoise{}, T_base_imu, 1);
  const ImuSample s = imu.TrueSample(k, 0.5);
  const Eigen::Matrix3d R_world_imu = k.T_world_base.linear() * T_base_imu.linear();
  EXPECT_LT((R_world_imu * s.accel_mps2 - Eigen::Vector3d(0, 0, kGravity_mps2)).norm(), 1e-12);
  EXPECT_LT(s.gyro_radps.norm(), 1e-15);
  EXPECT_EQ(s.t_s, 0.5);
}

// Static rig, 10 s at 200 Hz, no turn-on bias. After removing the exposed true bias, the mean of N samples has
// per-axis sigma = (density * sqrt(rate)) / sqrt(N) = density / sqrt(T) = 2.26e-3 / sqrt(10) = 7.1e-4 m/s^2;
// bound 4 sigma. The raw mean also carries the walk's time average, sigma_walk * sqrt(T / 3) = 5.5e-4.
TEST(ImuModel, StaticAccelMeanReadsGravityUpWithinNoise) {
  const ImuNoise noise;
  ImuModel imu(noise, Pose3::Identity(), 2024, ImuErrorConfig{0.0, 0.0});
  const double T = 10.0, dt = 1.0 / noise.rate_hz;
  const int n = static_cast<int>(std::lround(T * noise.rate_hz));
  Eigen::Vector3d mean_raw = Eigen::Vector3d::Zero(), mean_debiased = Eigen::Vector3d::Zero();
  Eigen::Vector3d white_sq = Eigen::Vector3d::Zero();
  const Eigen::Vector3d up(0, 0, kGravity_mps2);
  for (int i = 0; i < n; ++i) {
    const ImuSample s = imu.Sample(BaseKinematics{}, i * dt);
    mean_raw += s.accel_mps2 / n;
    mean_debiased += (s.accel_mps2 - imu.Bias().accel_mps2) / n;
    white_sq += (s.accel_mps2 - imu.Bias().accel_mps2 - up).cwiseAbs2() / n;
  }
  const double sigma_mean = noise.accel_noise_density / std::sqrt(T);
  const double sigma_raw = std::hypot(sigma_mean, noise.accel_random_walk * std::sqrt(T / 3));
  std::printf("debiased mean error %.3g (4 sigma %.3g), raw %.3g (4 sigma %.3g)\n", (mean_debiased - up).norm(),
              4 * sigma_mean, (mean_raw - up).norm(), 4 * sigma_raw);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(mean_debiased[a], up[a], 4 * sigma_mean) << "axis " << a;
    EXPECT_NEAR(mean_raw[a], up[a], 4 * sigma_raw) << "axis " << a;
    // Discrete white sigma = density * sqrt(rate) = 0.032 m/s^2; the sample std of 2000 draws is within
    // ~1.6 % (1 sigma), bound 8 %.
    EXPECT_NEAR(std::sqrt(white_sq[a]), noise.accel_noise_density * std::sqrt(noise.rate_hz),
                0.08 * noise.accel_noise_density * std::sqrt(noise.rate_hz));
  }
}

// Lever arm: the noise-free accelerometer equals the second derivative of the IMU site's world position
// (minus gravity) rotated into the imu frame. Second central difference, h = 1e-3 s: truncation
// h^2/12 * |p''''| <= 1e-6/12 * ~700 m/s^4 (2 Hz bounce + nod at 0.2 m lever arm) ~ 6e-5; round-off
// 4 * 1e-16 * 3 m / h^2 ~ 1e-9. Bound 5e-4 m/s^2.
TEST(ImuModel, LeverArmAccelMatchesNumericSecondDerivative) {
  const Pose3 T_base_imu = TiltedImuMount();
  const ScriptedBaseMotion motion{ScriptedBaseMotionConfig{}};
  const ImuModel imu(ImuNoise{}, T_base_imu, 1);
  const double h = 1e-3;
  double max_err = 0;
  for (double t = 0.05; t < 20.0; t += 0.173) {
    auto p = [&](double tt) -> Eigen::Vector3d { return (motion.At(tt).T_world_base * T_base_imu).translation(); };
    const Eigen::Vector3d a_num = (p(t + h) - 2 * p(t) + p(t - h)) / (h * h);
    const BaseKinematics k = motion.At(t);
    const Eigen::Matrix3d R_world_imu = k.T_world_base.linear() * T_base_imu.linear();
    const Eigen::Vector3d f_num = R_world_imu.transpose() * (a_num - GravityWorld());
    const ImuSample s = imu.TrueSample(k, t);
    max_err = std::max(max_err, (s.accel_mps2 - f_num).norm());
    EXPECT_LT((s.gyro_radps - T_base_imu.linear().transpose() * k.omega_base_radps).norm(), 1e-15);
  }
  std::printf("max |f - f_num| = %.3g m/s^2\n", max_err);
  EXPECT_LT(max_err, 5e-4);
}

/// Integrates gyro samples (minus `bias`) with the trapezoid rule on SO(3) and returns
/// |Log(R_true(T)^T R_integrated(T))| for the scripted motion over [0, T].
double GyroIntegrationError(ImuModel& imu, bool noisy, bool subtract_turn_on, double T) {
  const ScriptedBaseMotion motion{ScriptedBaseMotionConfig{}};
  const double dt = 1.0 / imu.noise().rate_hz;
  const int n = static_cast<int>(std::lround(T / dt));
  const Eigen::Vector3d b0 = subtract_turn_on ? imu.Bias().gyro_radps : Eigen::Vector3d::Zero();
  const Eigen::Matrix3d R_imu_base = imu.T_base_imu().linear().transpose();
  auto gyro = [&](int i) {
    const BaseKinematics k = motion.At(i * dt);
    const Eigen::Vector3d w = noisy ? imu.Sample(k, i * dt).gyro_radps : imu.TrueSample(k, i * dt).gyro_radps;
    return Eigen::Vector3d(w - b0);
  };
  Eigen::Matrix3d R_world_imu = motion.At(0).T_world_base.linear() * R_imu_base.transpose();
  Eigen::Vector3d w_prev = gyro(0);
  for (int i = 1; i <= n; ++i) {
    const Eigen::Vector3d w = gyro(i);
    R_world_imu = R_world_imu * ExpSO3(0.5 * (w_prev + w) * dt);
    w_prev = w;
  }
  const Eigen::Matrix3d R_true = motion.At(n * dt).T_world_base.linear() * R_imu_base.transpose();
  return LogSO3(R_true.transpose() * R_world_imu).norm();
}

// Integrating the gyro for T = 10 s along the scripted loop. The angle error per axis has
//   white noise:  sigma_g * sqrt(T)          (ImuNoise{}: 2.44e-4 * 3.16 = 7.7e-4 rad; BMI055 the same)
//   bias walk:    sigma_bg * T^1.5 / sqrt(3) (ImuNoise{}: 2.0e-5 * 31.6 / 1.73 = 3.7e-4 rad; BMI055 4.9e-5)
// (the turn-on bias is the exposed Bias() at start and is subtracted), total sigma 8.5e-4 rad (ImuNoise{}) and
// 7.7e-4 rad (BMI055) per axis, isotropic; the norm of the 3-vector exceeds 4 sigma with probability ~1e-3
// (chi, 3 dof). The trapezoid discretisation error, measured noise-free below, is added to the bound.
TEST(ImuModel, IntegratedGyroReproducesTrueRotationWithinNoiseBound) {
  const double T = 10.0;
  for (const ImuNoise& noise : {ImuNoise{}, Bmi055Noise()}) {
    ImuModel clean(noise, TiltedImuMount(), 5);
    const double discretisation = GyroIntegrationError(clean, false, false, T);
    std::printf("noise-free trapezoid error over %.0f s: %.3g rad\n", T, discretisation);
    EXPECT_LT(discretisation, 1e-4);
    const double sigma = std::sqrt(noise.gyro_noise_density * noise.gyro_noise_density * T +
                                   noise.gyro_random_walk * noise.gyro_random_walk * T * T * T / 3.0);
    for (uint64_t seed : {5u, 6u, 7u}) {
      ImuModel imu(noise, TiltedImuMount(), seed);
      const double err = GyroIntegrationError(imu, true, true, T);
      std::printf("seed %lu: noisy error %.3g rad (sigma %.3g, bound %.3g)\n", static_cast<unsigned long>(seed),
                  err, sigma, 4 * sigma + discretisation);
      EXPECT_LT(err, 4 * sigma + discretisation);
    }
    // Without subtracting the turn-on bias (sigma 0.003 rad/s per axis) the error is ~0.05 rad: far larger.
    ImuModel biased(noise, TiltedImuMount(), 5);
    EXPECT_GT(GyroIntegrationError(biased, true, false, T), 10 * sigma);
  }
}

TEST(ImuModel, SameSeedIdenticalDifferentSeedDifferent) {
  const ScriptedBaseMotion motion{ScriptedBaseMotionConfig{}};
  ImuErrorConfig errors;
  errors.gyro_scale_sigma = errors.accel_scale_sigma = 0.01;
  errors.gyro_misalignment_sigma_rad = errors.accel_misalignment_sigma_rad = 0.005;
  ImuModel a(ImuNoise{}, TiltedImuMount(), 99, errors), b(ImuNoise{}, TiltedImuMount(), 99, errors),
      c(ImuNoise{}, TiltedImuMount(), 100, errors);
  EXPECT_EQ(a.Bias().gyro_radps, b.Bias().gyro_radps);
  EXPECT_NE(a.Bias().gyro_radps, c.Bias().gyro_radps);
  EXPECT_EQ(a.GyroErrorMatrix(), b.GyroErrorMatrix());
  EXPECT_NE(a.AccelErrorMatrix(), c.AccelErrorMatrix());
  for (int i = 0; i < 500; ++i) {
    const double t = i * 0.005;
    const BaseKinematics k = motion.At(t);
    const ImuSample sa = a.Sample(k, t), sb = b.Sample(k, t), sc = c.Sample(k, t);
    ASSERT_EQ(sa.gyro_radps, sb.gyro_radps);
    ASSERT_EQ(sa.accel_mps2, sb.accel_mps2);
    ASSERT_EQ(a.Bias().accel_mps2, b.Bias().accel_mps2);
    ASSERT_NE(sa.gyro_radps, sc.gyro_radps);
    ASSERT_NE(sa.accel_mps2, sc.accel_mps2);
  }
}

// Sample(k, t) is SampleFromTruth(TrueSample(k, t)): the same seed gives bit-identical samples either way, and
// with default errors (no scale/misalignment) the error matrices are exactly the identity.
TEST(ImuModel, SampleFromTruthEqualsSampleOnTheSameTruth) {
  const ScriptedBaseMotion motion{ScriptedBaseMotionConfig{}};
  ImuModel a(Bmi055Noise(), TiltedImuMount(), 7), b(Bmi055Noise(), TiltedImuMount(), 7);
  EXPECT_EQ(a.GyroErrorMatrix(), Eigen::Matrix3d::Identity());
  EXPECT_EQ(a.AccelErrorMatrix(), Eigen::Matrix3d::Identity());
  for (int i = 0; i < 300; ++i) {
    const double t = 0.003 + i * 0.005;
    const ImuSample truth = a.TrueSample(motion.At(t), t);
    const ImuSample sa = a.Sample(motion.At(t), t);
    const ImuSample sb = b.SampleFromTruth(truth.gyro_radps, truth.accel_mps2, t);
    ASSERT_EQ(sa.t_s, t);
    ASSERT_EQ(sa.t_s, sb.t_s);
    ASSERT_EQ(sa.gyro_radps, sb.gyro_radps);
    ASSERT_EQ(sa.accel_mps2, sb.accel_mps2);
  }
}

// Without noise and turn-on bias the measurement is exactly M * truth. M = (I + diag(s)) (I + A): over 400 seeds
// the diagonal's spread is the scale sigma and the off-diagonal's the misalignment sigma (sample std of 1200 and
// 2400 draws: ~2 % and ~1.5 % relative sigma; bound 8 %), and the means are 1 and 0 within 4 sigma / sqrt(n).
TEST(ImuModel, ScaleAndMisalignmentAppliedAsConfigured) {
  ImuNoise silent = Bmi055Noise();
  silent.gyro_noise_density = silent.accel_noise_density = silent.gyro_random_walk = silent.accel_random_walk = 0;
  ImuErrorConfig errors;
  errors.gyro_turn_on_sigma_radps = errors.accel_turn_on_sigma_mps2 = 0;
  errors.gyro_scale_sigma = 0.02;
  errors.accel_scale_sigma = 0.01;
  errors.gyro_misalignment_sigma_rad = 0.004;
  errors.accel_misalignment_sigma_rad = 0.008;
  const Eigen::Vector3d w(0.3, -1.2, 0.7), f(1.0, 2.0, 9.5);
  double diag_sq[2] = {0, 0}, off_sq[2] = {0, 0}, diag_sum[2] = {0, 0}, off_sum[2] = {0, 0};
  const int seeds = 400;
  for (int seed = 0; seed < seeds; ++seed) {
    ImuModel imu(silent, TiltedImuMount(), uint64_t(seed), errors);
    const ImuSample s = imu.SampleFromTruth(w, f, 1.0);
    ASSERT_LT((s.gyro_radps - imu.GyroErrorMatrix() * w).norm(), 1e-15);
    ASSERT_LT((s.accel_mps2 - imu.AccelErrorMatrix() * f).norm(), 1e-14);
    const Eigen::Matrix3d* M[2] = {&imu.GyroErrorMatrix(), &imu.AccelErrorMatrix()};
    for (int g = 0; g < 2; ++g)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
          // Off-diagonal of (I + S)(I + A) is (1 + s_r) A_rc: divide the scale back out.
          const double v = r == c ? (*M[g])(r, c) - 1.0 : (*M[g])(r, c) / (*M[g])(r, r);
          (r == c ? diag_sq : off_sq)[g] += v * v;
          (r == c ? diag_sum : off_sum)[g] += v;
        }
  }
  const double scale_sigma[2] = {errors.gyro_scale_sigma, errors.accel_scale_sigma};
  const double mis_sigma[2] = {errors.gyro_misalignment_sigma_rad, errors.accel_misalignment_sigma_rad};
  for (int g = 0; g < 2; ++g) {
    const double n_diag = 3.0 * seeds, n_off = 6.0 * seeds;
    std::printf("%s: scale std %.4g (cfg %.4g), misalignment std %.4g (cfg %.4g)\n", g ? "accel" : "gyro",
                std::sqrt(diag_sq[g] / n_diag), scale_sigma[g], std::sqrt(off_sq[g] / n_off), mis_sigma[g]);
    EXPECT_NEAR(std::sqrt(diag_sq[g] / n_diag), scale_sigma[g], 0.08 * scale_sigma[g]);
    EXPECT_NEAR(std::sqrt(off_sq[g] / n_off), mis_sigma[g], 0.08 * mis_sigma[g]);
    EXPECT_NEAR(diag_sum[g] / n_diag, 0.0, 4 * scale_sigma[g] / std::sqrt(n_diag));
    EXPECT_NEAR(off_sum[g] / n_off, 0.0, 4 * mis_sigma[g] / std::sqrt(n_off));
  }
}

// The clock offset moves only the stamp: values are bit-identical to a model without offset (same seed).
TEST(ImuModel, ClockOffsetShiftsOnlyTheStamp) {
  ImuErrorConfig shifted;
  shifted.imu_clock_offset_s = -0.0125;
  ImuModel a(Bmi055Noise(), TiltedImuMount(), 3), b(Bmi055Noise(), TiltedImuMount(), 3, shifted);
  for (int i = 0; i < 100; ++i) {
    const double t = i * 0.005;
    const ImuSample sa = a.Sample(StaticBase(), t), sb = b.Sample(StaticBase(), t);
    ASSERT_EQ(sb.t_s, t - 0.0125);
    ASSERT_EQ(sa.gyro_radps, sb.gyro_radps);
    ASSERT_EQ(sa.accel_mps2, sb.accel_mps2);
  }
}

// The IMU clock's drift of D ppm moves the stamp at true time t by D * 1e-6 * t (checked at two times), on top
// of the offset; the values stay those of a model with a perfect clock.
TEST(ImuModel, ClockDriftGrowsWithTime) {
  ImuErrorConfig drifting;
  drifting.imu_clock_offset_s = 0.002;
  drifting.imu_clock_drift_ppm = -40.0;
  ImuModel a(Bmi055Noise(), TiltedImuMount(), 3), b(Bmi055Noise(), TiltedImuMount(), 3, drifting);
  for (const double t : {5.0, 500.0}) {
    const ImuSample sa = a.Sample(StaticBase(), t), sb = b.Sample(StaticBase(), t);
    EXPECT_EQ(sa.t_s, t);
    EXPECT_NEAR(sb.t_s - t, 0.002 - 40e-6 * t, 1e-12);  // -0.2 ms + 2 ms at 5 s; -20 ms + 2 ms at 500 s
    EXPECT_EQ(sa.gyro_radps, sb.gyro_radps);
  }
  drifting.imu_clock_drift_ppm = 1500.0;
  std::string error;
  EXPECT_FALSE(drifting.Validate(&error));
  EXPECT_NE(error.find("imu_clock_drift_ppm"), std::string::npos) << error;
}

TEST(ImuModel, ValidationNamesTheField) {
  std::string error;
  ImuNoise noise;
  noise.rate_hz = 0.0;
  EXPECT_FALSE(ValidateImuNoise(noise, &error));
  EXPECT_NE(error.find("rate_hz"), std::string::npos) << error;
  noise = {};
  noise.accel_random_walk = -1;
  EXPECT_FALSE(ValidateImuNoise(noise, &error));
  EXPECT_NE(error.find("accel_random_walk"), std::string::npos) << error;
  EXPECT_FALSE((ImuErrorConfig{-1.0, 0.0}.Validate(&error)));
  EXPECT_NE(error.find("gyro_turn_on_sigma_radps"), std::string::npos) << error;
  ImuErrorConfig e;
  e.accel_misalignment_sigma_rad = 0.5;
  EXPECT_FALSE(e.Validate(&error));
  EXPECT_NE(error.find("accel_misalignment_sigma_rad"), std::string::npos) << error;
  e = {};
  e.imu_clock_offset_s = std::nan("");
  EXPECT_FALSE(e.Validate(&error));
  EXPECT_NE(error.find("imu_clock_offset_s"), std::string::npos) << error;
  EXPECT_TRUE(ImuConfig{}.Validate(&error)) << error;
}

// Bmi055Noise: the datasheet densities converted to SI (docs/noise_models.md).
TEST(ImuModel, Bmi055NoiseConvertsTheDatasheetUnits) {
  const ImuNoise n = Bmi055Noise();
  EXPECT_NEAR(n.gyro_noise_density, 2.443e-4, 1e-7);   // 0.014 deg/s/sqrt(Hz)
  EXPECT_NEAR(n.accel_noise_density, 1.471e-3, 1e-6);  // 150 ug/sqrt(Hz)
  EXPECT_EQ(n.rate_hz, 200.0);
}

std::string Emit(const ImuConfig& c) {
  YAML::Emitter out;
  EmitImuConfig(out, c);
  return out.c_str();
}

TEST(ImuYaml, RoundTripKeepsEveryField) {
  ImuConfig c;
  c.noise.rate_hz = 400.0;
  c.noise.gyro_noise_density = 1.234567890123e-4;
  c.noise.accel_random_walk = 7.7e-5;
  c.errors.gyro_turn_on_sigma_radps = 0.0011;
  c.errors.accel_scale_sigma = 0.013;
  c.errors.gyro_misalignment_sigma_rad = 0.0021;
  c.errors.imu_clock_offset_s = 0.0035;
  c.errors.imu_clock_drift_ppm = -12.5;
  const std::string text = Emit(c);
  ImuConfig back;
  const Status s = ParseImuConfig("mem.yaml", YAML::Load(text), &back);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(Emit(back), text);
  EXPECT_EQ(back.noise.gyro_noise_density, c.noise.gyro_noise_density);
  EXPECT_EQ(back.noise.accel_random_walk, c.noise.accel_random_walk);
  EXPECT_EQ(back.noise.rate_hz, 400.0);
  EXPECT_EQ(back.errors.accel_scale_sigma, 0.013);
  EXPECT_EQ(back.errors.imu_clock_offset_s, 0.0035);
  EXPECT_EQ(back.errors.imu_clock_drift_ppm, -12.5);
}

TEST(ImuYaml, PresetThenOverrides) {
  ImuConfig c;
  c.noise = ImuNoise{};
  ASSERT_TRUE(ParseImuConfig("mem.yaml", YAML::Load("preset: bmi055\nrate_hz: 100\n"), &c).ok);
  EXPECT_EQ(c.noise.rate_hz, 100.0);
  EXPECT_EQ(c.noise.gyro_noise_density, Bmi055Noise().gyro_noise_density);
  EXPECT_EQ(c.noise.accel_noise_density, Bmi055Noise().accel_noise_density);
}

std::string ParseError(const std::string& text) {
  ImuConfig c;
  const Status s = ParseImuConfig("imu.yaml", YAML::Load(text), &c);
  return s.ok ? "" : s.message;
}

TEST(ImuYaml, ErrorsNameFileLineAndField) {
  std::string e = ParseError("rate_hz: 200\ngyro_noise_density: 1e-4\ngyro_nosie_density: 2e-4\n");
  EXPECT_NE(e.find("imu.yaml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("gyro_nosie_density"), std::string::npos) << e;
  e = ParseError("rate_hz: 200\naccel_scale_sigma: fast\n");
  EXPECT_NE(e.find("imu.yaml:2"), std::string::npos) << e;
  EXPECT_NE(e.find("accel_scale_sigma"), std::string::npos) << e;
  e = ParseError("gyro_turn_on_sigma_radps: -0.1\n");
  EXPECT_NE(e.find("imu.yaml:1"), std::string::npos) << e;
  EXPECT_NE(e.find("gyro_turn_on_sigma_radps"), std::string::npos) << e;
  e = ParseError("preset: adis16448\n");
  EXPECT_NE(e.find("preset"), std::string::npos) << e;
  ImuConfig unchanged;
  unchanged.noise.rate_hz = 123;
  EXPECT_FALSE(ParseImuConfig("imu.yaml", YAML::Load("rate_hz: -5\n"), &unchanged).ok);
  EXPECT_EQ(unchanged.noise.rate_hz, 123) << "a failed parse must leave the config untouched";
}

}  // namespace
}  // namespace rotolidar::sim
