// IMU initialisation: static start (roll/pitch, gyro bias, stillness test) and moving start (gyro bias, velocities,
// gravity direction from LiDAR-only poses + preintegration), on synthetic data with seeded Kalibr noise.
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "core/backend/imu_init.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {
namespace {

const Eigen::Vector3d kGravity(0.0, 0.0, -9.81);
constexpr double kRateHz = 200.0;

Eigen::Vector3d Noise(RandomStream& rng, double sigma) {
  return {rng.Normal(0.0, sigma), rng.Normal(0.0, sigma), rng.Normal(0.0, sigma)};
}

Eigen::Matrix3d Rpy(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX())).toRotationMatrix();
}

/// Angle [rad] between the gravity directions that two orientations imply (yaw-free tilt error).
double TiltError(const Eigen::Matrix3d& R_world_imu_a, const Eigen::Matrix3d& R_world_imu_b) {
  const Eigen::Vector3d up_a = R_world_imu_a.transpose().col(2), up_b = R_world_imu_b.transpose().col(2);
  return std::atan2(up_a.cross(up_b).norm(), up_a.dot(up_b));
}

/// Kalibr white noise per sample at kRateHz (ImuNoise defaults): density * sqrt(rate).
void AddWhiteNoise(RandomStream& rng, ImuSample* s) {
  const ImuNoise n;
  s->gyro_radps += Noise(rng, n.gyro_noise_density * std::sqrt(kRateHz));
  s->accel_mps2 += Noise(rng, n.accel_noise_density * std::sqrt(kRateHz));
}

/// A still IMU at orientation R with biases, optionally rocking about x at rock_radps amplitude (not still).
std::vector<ImuSample> StillSamples(const Eigen::Matrix3d& R, const Eigen::Vector3d& bg, const Eigen::Vector3d& ba,
                                    double duration_s, double rock_radps = 0.0) {
  RandomStream rng(3, "imu_init_test.static");
  std::vector<ImuSample> out;
  for (int k = 0; k <= static_cast<int>(duration_s * kRateHz); ++k) {
    ImuSample s;
    s.t_s = k / kRateHz;
    s.gyro_radps = bg + Eigen::Vector3d(rock_radps * std::sin(6.0 * s.t_s), 0.0, 0.0);
    s.accel_mps2 = R.transpose() * (-kGravity) + ba;
    AddWhiteNoise(rng, &s);
    out.push_back(s);
  }
  return out;
}

TEST(ImuInit, StaticRecoversRollPitchAndGyroBias) {
  const Eigen::Matrix3d R = Rpy(0.1, -0.2, 0.7);
  const Eigen::Vector3d bg(0.01, -0.005, 0.02);
  const ImuInitResult r = InitializeStatic(StillSamples(R, bg, Eigen::Vector3d::Zero(), 2.0), ImuInitConfig{});
  ASSERT_TRUE(r.success) << r.reason;
  const double tilt = TiltError(r.R_world_imu, R), bg_err = (r.bias_gyro_radps - bg).norm();
  // Yaw is unobservable and set to 0: the recovered orientation is R up to a rotation about world z.
  const Eigen::Vector3d ypr = r.R_world_imu.eulerAngles(2, 1, 0);
  std::printf("[measured] static: tilt %.2e rad, bg %.2e rad/s, yaw %.2e, |g| residual %.2e\n", tilt, bg_err,
              ypr(0), r.gravity_residual_mps2);
  // 201 samples in the 1 s window. 1-sigma predictions: tilt 0.032 / (9.81 sqrt(201)) = 2.3e-4 rad per axis, gyro
  // bias 3.5e-3 / sqrt(201) = 2.4e-4 rad/s per axis. Measured tilt 3.2e-4 rad, |bg error| 2.8e-4 rad/s. Bounds are
  // ~3-4 sigma of the 2-D / 3-D norms.
  EXPECT_LT(tilt, 1e-3);
  EXPECT_LT(bg_err, 1.7e-3);
  EXPECT_LT(std::abs(ypr(0)), 1e-12);
  EXPECT_EQ(r.velocities_world_mps.size(), 1u);
  EXPECT_LT(r.gravity_residual_mps2, 0.02);
  EXPECT_NEAR(r.t_s, 1.0, 1e-12);
}

TEST(ImuInit, StaticTiltErrorEqualsAccelBiasOverGravity) {
  // The documented limitation: an accelerometer bias perpendicular to gravity reads as a tilt of |ba| / g.
  const Eigen::Matrix3d R = Rpy(0.0, 0.0, 0.0);
  const ImuInitResult r =
      InitializeStatic(StillSamples(R, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.1, 0.0, 0.0), 2.0), {});
  ASSERT_TRUE(r.success) << r.reason;
  // Expected 0.1 / 9.81 = 1.02e-2 rad, plus the noise (2.3e-4 rad, 1 sigma).
  EXPECT_NEAR(TiltError(r.R_world_imu, R), 0.1 / 9.81, 1e-3);
}

TEST(ImuInit, StaticRejectsMotionAndShortData) {
  const Eigen::Matrix3d R = Rpy(0.1, 0.1, 0.0);
  const ImuInitResult rocking =
      InitializeStatic(StillSamples(R, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 2.0, 0.2), {});
  EXPECT_FALSE(rocking.success);
  EXPECT_NE(rocking.reason.find("not still"), std::string::npos) << rocking.reason;
  const ImuInitResult short_data =
      InitializeStatic(StillSamples(R, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.5), {});
  EXPECT_FALSE(short_data.success);
  EXPECT_NE(short_data.reason.find("static_window_s"), std::string::npos) << short_data.reason;
  EXPECT_FALSE(InitializeStatic({}, {}).success);
}

TEST(ImuIsStill, AcceptsARestingVibratingRigAndRejectsMotion) {
  const Eigen::Matrix3d R = Rpy(0.05, -0.1, 0.3);
  // A consumer gyro's turn-on bias (BMI055: up to 1 deg/s per axis) is still "still".
  const Eigen::Vector3d bg(0.017, -0.017, 0.017);
  std::vector<ImuSample> still = StillSamples(R, bg, Eigen::Vector3d::Zero(), 2.0);
  const ImuInitConfig c;
  std::string why;
  EXPECT_TRUE(ImuIsStill(still, 0.0, 1.0, c, &why)) << why;
  // Stepper vibration, as the harsh twin's stepper shakes a standing rig (0.4 m/s^2 per axis over 1 s): lines
  // at 50 and 200 steps per rotor turn (20.7 and 82.8 Hz at 2.6 rad/s), 0.5 and 0.25 m/s^2 amplitude per axis.
  std::vector<ImuSample> shaken = still;
  for (ImuSample& s : shaken) {
    const double shake = 0.5 * std::sin(2 * M_PI * 20.7 * s.t_s + 0.3) + 0.25 * std::sin(2 * M_PI * 82.8 * s.t_s);
    s.accel_mps2 += shake * Eigen::Vector3d::Ones();
  }
  EXPECT_TRUE(ImuIsStill(shaken, 0.0, 1.0, c, &why)) << why;
  // Judged per sample (no low-pass) the same shake reads as motion: the premise of static_block_s.
  ImuInitConfig per_sample = c;
  per_sample.static_block_s = 0.0;
  EXPECT_FALSE(ImuIsStill(shaken, 0.0, 1.0, per_sample, &why));
  // The first scan's window holds one block (0.1 s of samples): the samples' spread against 4x the thresholds.
  EXPECT_TRUE(ImuIsStill(shaken, -0.9, 0.1, c, &why)) << why;
  // A walk's 2 Hz, 0.6 m/s^2 bounce is not still, shaken or not; nor a slow 0.2 rad/s turn (std small, mean
  // large); nor a tilt away from gravity's magnitude; nor too few samples.
  std::vector<ImuSample> bounce = shaken;
  for (ImuSample& s : bounce) s.accel_mps2.z() += 0.85 * std::sin(2 * M_PI * 2.0 * s.t_s);
  EXPECT_FALSE(ImuIsStill(bounce, 0.0, 1.0, c, &why));
  EXPECT_NE(why.find("accel std"), std::string::npos) << why;
  EXPECT_FALSE(ImuIsStill(StillSamples(R, Eigen::Vector3d(0.0, 0.0, 0.2), Eigen::Vector3d::Zero(), 2.0), 0.0, 1.0,
                          c, &why));
  EXPECT_NE(why.find("mean gyro"), std::string::npos) << why;
  EXPECT_FALSE(ImuIsStill(StillSamples(R, bg, Eigen::Vector3d(0.0, 0.0, 1.0), 2.0), 0.0, 1.0, c, &why));
  EXPECT_NE(why.find("mean accel"), std::string::npos) << why;
  EXPECT_FALSE(ImuIsStill(still, 0.0, 0.05, c, &why));  // 11 samples < static_min_samples = 20
  EXPECT_NE(why.find("static_min_samples"), std::string::npos) << why;
}

TEST(ImuIsStill, SeesTheFirstStepsWithinAFewTenthsOfASecond) {
  // Standing, then a 1 m/s^2 push along x from t = 1 s (a walk's or a vehicle's start): the 1 s window that
  // ends 0.15 s after the push has 0.2 s blocks of 0, 0, 0, 0 and 0.75 m/s^2, a spread of 0.3 m/s^2 > 0.15.
  std::vector<ImuSample> start =
      StillSamples(Rpy(0.0, 0.0, 0.0), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 2.0);
  for (ImuSample& s : start)
    if (s.t_s >= 1.0) s.accel_mps2.x() += 1.0;
  const ImuInitConfig c;
  std::string why;
  EXPECT_TRUE(ImuIsStill(start, 0.0, 1.0 - 1e-9, c, &why)) << why;
  EXPECT_FALSE(ImuIsStill(start, 0.15, 1.15, c, &why));
  EXPECT_NE(why.find("accel std"), std::string::npos) << why;
  // A run that starts walking: its first scan (one block) is judged per sample, and a walk's spread fails.
  std::vector<ImuSample> walk = start;
  for (ImuSample& s : walk) s.accel_mps2.z() += 3.0 * std::sin(2 * M_PI * 2.0 * s.t_s);
  EXPECT_FALSE(ImuIsStill(walk, -0.9, 0.1, c, &why));
}

TEST(ImuInitConfig, StaticBlockNeedsTwoBlocks) {
  ImuInitConfig c;
  std::string error;
  c.static_block_s = 0.6;  // > static_window_s / 2
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("static_block_s"), std::string::npos) << error;
  c.static_block_s = -0.1;
  EXPECT_FALSE(c.Validate(&error));
  c.static_block_s = 0.0;
  EXPECT_TRUE(c.Validate(&error)) << error;
}

/// Motion for the moving start: R = Rz Ry Rx of smooth angles, p sinusoidal (|v| ~1 m/s, |a| ~1 m/s^2).
struct Motion {
  static Eigen::Vector3d Angles(double t) {
    return {0.2 * std::sin(1.1 * t), 0.15 * std::sin(0.8 * t + 0.3), 0.5 * t};
  }
  static Eigen::Vector3d AngleRates(double t) {
    return {0.22 * std::cos(1.1 * t), 0.12 * std::cos(0.8 * t + 0.3), 0.5};
  }
  static Eigen::Matrix3d R(double t) {
    const Eigen::Vector3d e = Angles(t);
    return Rpy(e.x(), e.y(), e.z());
  }
  static Eigen::Vector3d P(double t) {
    return {std::sin(1.2 * t) + 0.3 * t, 0.8 * (1.0 - std::cos(t)), 0.2 * std::sin(1.5 * t)};
  }
  static Eigen::Vector3d V(double t) {
    return {1.2 * std::cos(1.2 * t) + 0.3, 0.8 * std::sin(t), 0.3 * std::cos(1.5 * t)};
  }
  static Eigen::Vector3d A(double t) {
    return {-1.44 * std::sin(1.2 * t), 0.8 * std::cos(t), -0.45 * std::sin(1.5 * t)};
  }
  static ImuSample Sample(double t, const Eigen::Vector3d& bg) {
    const Eigen::Vector3d e = Angles(t), d = AngleRates(t);
    const Eigen::Matrix3d RxT = Rpy(e.x(), 0, 0).transpose(), RyT = Rpy(0, e.y(), 0).transpose();
    ImuSample s;
    s.t_s = t;
    s.gyro_radps = RxT * RyT * Eigen::Vector3d(0, 0, d.z()) + RxT * Eigen::Vector3d(0, d.y(), 0) +
                   Eigen::Vector3d(d.x(), 0, 0) + bg;
    s.accel_mps2 = R(t).transpose() * (A(t) - kGravity);
    return s;
  }
};

struct MovingCase {
  std::vector<Pose3> T_odom_imu;
  std::vector<PreintegratedImu> imu_between;
  Eigen::Matrix3d R_odom_world;
};

/// N poses at 10 Hz in a tilted odometry frame (LiDAR noise sigma_m / sigma_rad per axis), IMU at 200 Hz with the
/// gyro bias (and Kalibr white noise when noisy), preintegrated at zero bias.
MovingCase MakeMovingCase(int n, double sigma_m, double sigma_rad, bool noisy, const Eigen::Vector3d& bg) {
  RandomStream lidar(9, "imu_init_test.lidar"), imu(9, "imu_init_test.imu");
  MovingCase c;
  c.R_odom_world = Rpy(0.25, -0.15, 1.0);  // odom = the first base frame: tilted, arbitrary heading
  const Pose3 T_odom_world = MakePose(Eigen::Vector3d(0.5, -1.0, 0.2), Eigen::Quaterniond(c.R_odom_world));
  for (int k = 0; k < n; ++k) {
    const double t = 0.1 * k;
    const Eigen::Vector3d p_world_m = Motion::P(t) + Noise(lidar, sigma_m);  // drawn first, then the rotation
    const Pose3 T_world_imu = MakePose(p_world_m, Eigen::Quaterniond(ExpSO3(Noise(lidar, sigma_rad)) * Motion::R(t)));
    c.T_odom_imu.push_back(T_odom_world * T_world_imu);
    if (k + 1 == n) break;
    PreintegratedImu pre(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), ImuNoise{});
    ImuSample prev = Motion::Sample(t, bg);
    if (noisy) AddWhiteNoise(imu, &prev);
    for (int j = 1; j <= 20; ++j) {
      ImuSample next = Motion::Sample(t + j / kRateHz, bg);
      if (noisy) AddWhiteNoise(imu, &next);
      EXPECT_TRUE(pre.Integrate(prev, next).ok);
      prev = next;
    }
    c.imu_between.push_back(pre);
  }
  return c;
}

struct MovingErrors {
  double tilt_rad, vel_rms_mps, bg_err;
};

MovingErrors Evaluate(const MovingCase& c, const ImuInitResult& r, const Eigen::Vector3d& bg) {
  MovingErrors e{};
  // Gravity direction in odom: estimated vs true; velocities compared in odom (the world's yaw is arbitrary).
  const Eigen::Vector3d g_true_odom = c.R_odom_world * kGravity;
  e.tilt_rad = std::atan2(g_true_odom.cross(r.gravity_odom_mps2).norm(), g_true_odom.dot(r.gravity_odom_mps2));
  double sum = 0.0;
  for (size_t k = 0; k < r.velocities_world_mps.size(); ++k) {
    const Eigen::Vector3d v_odom = r.R_world_odom.transpose() * r.velocities_world_mps[k];
    sum += (v_odom - c.R_odom_world * Motion::V(0.1 * k)).squaredNorm();
  }
  e.vel_rms_mps = std::sqrt(sum / r.velocities_world_mps.size());
  e.bg_err = (r.bias_gyro_radps - bg).norm();
  return e;
}

TEST(ImuInit, MovingRecoversVelocityGravityAndGyroBias) {
  const Eigen::Vector3d bg(0.01, -0.02, 0.015);
  const MovingCase exact = MakeMovingCase(10, 0.0, 0.0, false, bg);
  const ImuInitResult re = InitializeMoving(exact.T_odom_imu, exact.imu_between, ImuInitConfig{});
  ASSERT_TRUE(re.success) << re.reason;
  const MovingErrors ee = Evaluate(exact, re, bg);
  const MovingCase noisy = MakeMovingCase(20, 0.01, 0.003, true, bg);
  const ImuInitResult rn = InitializeMoving(noisy.T_odom_imu, noisy.imu_between, ImuInitConfig{});
  ASSERT_TRUE(rn.success) << rn.reason;
  const MovingErrors en = Evaluate(noisy, rn, bg);
  std::printf("[measured] moving exact: tilt %.2e vel %.2e bg %.2e |g| res %.2e | noisy: tilt %.2e vel %.2e bg %.2e "
              "|g| res %.2e\n", ee.tilt_rad, ee.vel_rms_mps, ee.bg_err, re.gravity_residual_mps2, en.tilt_rad,
              en.vel_rms_mps, en.bg_err, rn.gravity_residual_mps2);
  // Exact data (10 poses, 0.9 s): only the 200 Hz midpoint discretisation remains. Measured tilt 7.1e-7 rad,
  // velocity RMS 3.3e-6 m/s, |bg error| 3.8e-7 rad/s, ||g| - 9.81| 2.9e-7. Bounds 10x.
  EXPECT_LT(ee.tilt_rad, 1e-5);
  EXPECT_LT(ee.vel_rms_mps, 3e-5);
  EXPECT_LT(ee.bg_err, 4e-6);
  // Noisy (20 poses over 1.9 s, LiDAR 1 cm / 3 mrad, Kalibr IMU noise). Gravity is the quadratic term of the
  // positions: sigma_g = 2 * 0.01 m / sqrt(sum P2(t_k)^2) = 0.015 m/s^2 per axis -> tilt ~1.5 mrad per axis from the
  // positions alone; the 3 mrad rotation noise of every pose adds to it. The gyro bias is the slope of the rotation
  // errors: 3 mrad / sqrt(sum (t_k - mean)^2) = 1.2e-3 rad/s per axis.
  // Measured over seeds 1-11: tilt 3.4e-3 to 1.33e-2 rad (median 7.4e-3), velocity RMS 7.7e-2 to 9.3e-2 m/s,
  // |bg error| 1.3e-3 to 4.9e-3 rad/s, ||g_lsq| - 9.81| 1.3e-2 to 0.17 m/s^2. Bounds ~1.5x the worst.
  // (With 10 poses over 0.9 s the same noise gives tilt 8.6e-3 rad, velocity RMS 0.12 m/s: the init wants ~2 s.)
  EXPECT_LT(en.tilt_rad, 0.02);
  EXPECT_LT(en.vel_rms_mps, 0.15);
  EXPECT_LT(en.bg_err, 0.008);
  EXPECT_LT(rn.gravity_residual_mps2, 0.25);
  // The world states are consistent with the result's rotations.
  ASSERT_EQ(rn.states.size(), 20u);
  EXPECT_LT((rn.states[0].R_world_imu - rn.R_world_imu).norm(), 1e-12);
  EXPECT_LT((rn.R_world_odom * rn.gravity_odom_mps2 - kGravity).norm(), 1e-9);
}

TEST(ImuInit, MovingRejectsBadInput) {
  const MovingCase c = MakeMovingCase(4, 0.0, 0.0, false, Eigen::Vector3d::Zero());
  const ImuInitResult few = InitializeMoving(c.T_odom_imu, c.imu_between, ImuInitConfig{});
  EXPECT_FALSE(few.success);
  EXPECT_NE(few.reason.find("moving_min_poses"), std::string::npos) << few.reason;
  std::vector<PreintegratedImu> short_imu(c.imu_between.begin(), c.imu_between.end() - 1);
  ImuInitConfig config;
  config.moving_min_poses = 3;
  const ImuInitResult mismatch = InitializeMoving(c.T_odom_imu, short_imu, config);
  EXPECT_FALSE(mismatch.success);
  EXPECT_NE(mismatch.reason.find("intervals"), std::string::npos) << mismatch.reason;
  EXPECT_TRUE(InitializeMoving(c.T_odom_imu, c.imu_between, config).success);
}

TEST(ImuInitConfig, ValidateNamesTheField) {
  std::string error;
  EXPECT_TRUE(ImuInitConfig{}.Validate(&error)) << error;
  ImuInitConfig c;
  c.static_window_s = 0.0;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("imu_init.static_window_s"), std::string::npos) << error;
  c = ImuInitConfig{};
  c.moving_min_poses = 2;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("imu_init.moving_min_poses"), std::string::npos) << error;
  c = ImuInitConfig{};
  c.static_max_accel_std_mps2 = -1.0;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("static_max_accel_std_mps2"), std::string::npos) << error;
  const ImuInitResult r = InitializeStatic(StillSamples(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(),
                                                        Eigen::Vector3d::Zero(), 2.0), c);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.reason.find("static_max_accel_std_mps2"), std::string::npos) << r.reason;
}

}  // namespace
}  // namespace rotolidar
