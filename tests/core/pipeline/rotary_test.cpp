// The rotary transform: encoder interpolation, unwrapping, and the uniform-rotation fallback.
#include <gtest/gtest.h>

#include "core/pipeline/rotary.hpp"

namespace rotolidar {
namespace {

RigCalib CalibWithEncoder(uint32_t counts) {
  RigCalib c;
  c.encoder.counts_per_rev = counts;
  c.motor_speed_radps = 2.0;
  return c;
}

uint32_t CountOf(double theta, uint32_t counts) {
  double x = std::fmod(theta / (2 * M_PI), 1.0);
  if (x < 0) x += 1.0;
  return uint32_t(std::floor(x * counts)) % counts;
}

TEST(RotorAngleInterpolator, TracksAConstantSpeedRotorAcrossWraps) {
  const RigCalib calib = CalibWithEncoder(16384);
  RotorAngleInterpolator rotor(calib);
  const double w = 3.0;  // rad/s: several wraps in 10 s
  for (int i = 0; i <= 10000; ++i) rotor.Add({i * 1e-3, CountOf(w * i * 1e-3, 16384)});
  // One 14-bit count is 0.38 mrad; the bin centre is within half a count of the truth.
  const double half_count = M_PI / 16384;
  for (double t = 0.0005; t < 10.0; t += 0.0137) {
    RotorAngleSource source;
    EXPECT_NEAR(rotor.AngleAt(t, &source), w * t, half_count + 1e-9) << t;
    EXPECT_EQ(source, RotorAngleSource::kEncoder);
  }
}

TEST(RotorAngleInterpolator, FallsBackToUniformRotationOutsideTheData) {
  const RigCalib calib = CalibWithEncoder(4096);
  RotorAngleInterpolator rotor(calib);
  rotor.Add({1.0, 0});
  rotor.Add({1.001, 1});
  RotorAngleSource source;
  const double at_end = rotor.AngleAt(1.001);
  EXPECT_NEAR(rotor.AngleAt(1.101, &source), at_end + calib.motor_speed_radps * 0.1, 1e-12);
  EXPECT_EQ(source, RotorAngleSource::kUniformFallback);
}

TEST(RotorAngleInterpolator, IgnoresOutOfOrderSamples) {
  RotorAngleInterpolator rotor(CalibWithEncoder(4096));
  EXPECT_TRUE(rotor.Add({1.0, 10}));
  EXPECT_FALSE(rotor.Add({0.5, 20}));
  EXPECT_FALSE(rotor.Add({1.0, 20}));
}

TEST(LidarToBase, ZeroAngleAppliesTheFixedExtrinsics) {
  RigCalib calib = CalibWithEncoder(4096);
  calib.T_base_motor = MakePose({0.1, 0, 0}, Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY())));
  calib.T_rotor_lidar = MakePose({0, 0, 0.08}, Eigen::Quaterniond::Identity());
  calib.encoder.zero_offset_rad = M_PI / 4096;  // makes count 0 decode to exactly 0 rad
  RotorAngleInterpolator rotor(calib);
  rotor.Add({0.0, 0});
  rotor.Add({1.0, 0});
  LidarScan scan;
  LidarPoint p;
  p.x_m = 1.0f;
  p.t_s = 0.5;
  scan.points.push_back(p);
  std::vector<Eigen::Vector3d> p_base;
  EXPECT_EQ(LidarToBase(calib, rotor, scan, &p_base), 0u);
  // lidar x -> rotor x -> motor x; Ry(90) maps motor x to base -z; motor z to base x; plus translations.
  EXPECT_TRUE(p_base[0].isApprox(Eigen::Vector3d(0.1 + 0.08, 0, -1.0), 1e-9)) << p_base[0].transpose();
}

// RotaryTransform (no trigonometry per point) equals the straightforward T_base_lidar(AngleAt(t)) * p: on an
// irregular encoder stream (jittered times, a fast stretch with > 0.1 rad per interval), points in and out of
// time order, on sample times exactly, and outside the buffered span (the uniform fallback).
TEST(RotaryTransform, EqualsDirectTransformWithAngleAt) {
  RigCalib calib = CalibWithEncoder(16384);
  calib.T_base_motor = MakePose({0.1, -0.02, 0.3}, Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized())));
  calib.T_rotor_lidar = MakePose({0.01, 0.02, 0.08}, Eigen::Quaterniond(Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitX())));
  RotorAngleInterpolator rotor(calib);
  std::vector<double> times;
  double t = 10.0, theta = 0.0;
  for (int i = 0; i < 400; ++i) {
    const double dt = 1e-3 * (0.5 + 0.01 * (i * 37 % 100));  // 0.5 .. 1.5 ms
    theta += (i > 200 && i < 220 ? 150.0 : 3.0) * dt;        // 150 rad/s: up to 0.22 rad per interval
    t += dt;
    rotor.Add({t, CountOf(theta, 16384)});
    times.push_back(t);
  }
  LidarScan scan;
  for (int i = 0; i < 3000; ++i) {
    LidarPoint p;
    p.x_m = 3.f + 0.001f * i, p.y_m = -1.f + 0.0005f * i, p.z_m = 0.5f;
    p.t_s = i % 50 == 0 ? times[i % times.size()] : times.front() - 0.01 + (times.back() - times.front() + 0.02) *
                                                                               ((i * 7919) % 3000) / 3000.0;
    scan.points.push_back(p);
  }
  std::vector<Eigen::Vector3d> p_base;
  size_t expected_fallback = 0;
  LidarToBase(calib, rotor, scan, &p_base);
  for (size_t i = 0; i < scan.points.size(); ++i) {
    const LidarPoint& p = scan.points[i];
    RotorAngleSource source;
    const double angle = rotor.AngleAt(p.t_s, &source);
    expected_fallback += source == RotorAngleSource::kUniformFallback;
    const Eigen::Vector3d direct =
        calib.T_base_motor * RotZ(angle) * calib.T_rotor_lidar * Eigen::Vector3d(p.x_m, p.y_m, p.z_m);
    ASSERT_LT((p_base[i] - direct).norm(), 1e-12) << i << " t " << p.t_s;
  }
  EXPECT_GT(expected_fallback, 0u);
  EXPECT_EQ(LidarToBase(calib, rotor, scan, &p_base), expected_fallback);
}

}  // namespace
}  // namespace rotolidar
