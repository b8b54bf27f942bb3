// The rotary transform: encoder interpolation, unwrapping, the uniform-rotation fallback, and DeskewScan (rotary
// transform + carrier motion in one pass) against plain references written here.
#include <type_traits>

#include <gtest/gtest.h>

#include "core/deskew/deskew.hpp"
#include "core/deskew/rotary.hpp"

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

/// The library's rotary path over a scan: RotaryTransform point by point; returns the fallback count.
size_t LidarToBase(const RotorAngleInterpolator& rotor, const LidarScan& scan, std::vector<Eigen::Vector3d>* p_base) {
  RotaryTransform rotary(rotor);
  p_base->resize(scan.points.size());
  size_t fallback = 0;
  for (size_t i = 0; i < scan.points.size(); ++i) {
    bool f = false;
    (*p_base)[i] = rotary.Apply(scan.points[i], &f);
    fallback += f;
  }
  return fallback;
}

/// Plain reference of the rotor angle: linear interpolation of unwrapped samples (t, theta) found by a linear
/// scan; outside them, the uniform model at speed w from the nearest sample. *fallback: outside the samples.
double PlainAngle(const std::vector<std::pair<double, double>>& samples, double w, double t, bool* fallback) {
  *fallback = t < samples.front().first || t > samples.back().first;
  if (t <= samples.front().first) return samples.front().second + w * (t - samples.front().first);
  if (t >= samples.back().first) return samples.back().second + w * (t - samples.back().first);
  size_t k = 1;
  while (samples[k].first <= t) ++k;
  const auto& [t0, a0] = samples[k - 1];
  const auto& [t1, a1] = samples[k];
  return a0 + (a1 - a0) * (t - t0) / (t1 - t0);
}

// Classes that keep a reference to their input refuse a temporary at compile time (it would dangle); the
// interpolator keeps its own copy of the calibration and takes one.
static_assert(!std::is_constructible_v<RotaryTransform, RotorAngleInterpolator>);
static_assert(std::is_constructible_v<RotaryTransform, const RotorAngleInterpolator&>);
static_assert(!std::is_constructible_v<MotionInterpolator, MotionTable>);
static_assert(std::is_constructible_v<MotionInterpolator, const MotionTable&>);
static_assert(std::is_constructible_v<RotorAngleInterpolator, RigCalib>);

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
  EXPECT_EQ(LidarToBase(rotor, scan, &p_base), 0u);
  // lidar x -> rotor x -> motor x; Ry(90) maps motor x to base -z; motor z to base x; plus translations.
  EXPECT_TRUE(p_base[0].isApprox(Eigen::Vector3d(0.1 + 0.08, 0, -1.0), 1e-9)) << p_base[0].transpose();
}

// RotaryTransform (no trigonometry per point) equals the plain T_base_lidar(PlainAngle(t)) * p: on an irregular
// encoder stream (jittered times, a fast stretch with > 0.1 rad per interval), points in and out of time order,
// on sample times exactly, and outside the buffered span (the uniform fallback). AngleAt agrees too.
TEST(RotaryTransform, EqualsPlainTransform) {
  RigCalib calib = CalibWithEncoder(16384);
  calib.T_base_motor = MakePose({0.1, -0.02, 0.3}, Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized())));
  calib.T_rotor_lidar = MakePose({0.01, 0.02, 0.08}, Eigen::Quaterniond(Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitX())));
  RotorAngleInterpolator rotor(calib);
  std::vector<double> times;
  std::vector<std::pair<double, double>> samples;  // (t, unwrapped decoded angle): what the encoder reported
  double t = 10.0, theta = 0.0;
  for (int i = 0; i < 400; ++i) {
    const double dt = 1e-3 * (0.5 + 0.01 * (i * 37 % 100));  // 0.5 .. 1.5 ms
    theta += (i > 200 && i < 220 ? 150.0 : 3.0) * dt;        // 150 rad/s: up to 0.22 rad per interval
    t += dt;
    const uint32_t count = CountOf(theta, 16384);
    rotor.Add({t, count});
    times.push_back(t);
    const double decoded = calib.EncoderAngle(count);
    samples.emplace_back(t, decoded + 2 * M_PI * std::round((theta - decoded) / (2 * M_PI)));
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
  const size_t fallback = LidarToBase(rotor, scan, &p_base);
  for (size_t i = 0; i < scan.points.size(); ++i) {
    const LidarPoint& p = scan.points[i];
    bool outside = false;
    const double angle = PlainAngle(samples, calib.motor_speed_radps, p.t_s, &outside);
    expected_fallback += outside;
    RotorAngleSource source;
    ASSERT_NEAR(rotor.AngleAt(p.t_s, &source), angle, 1e-12) << i;
    ASSERT_EQ(source == RotorAngleSource::kUniformFallback, outside) << i;
    const Eigen::Vector3d direct =
        calib.T_base_motor * RotZ(angle) * calib.T_rotor_lidar * Eigen::Vector3d(p.x_m, p.y_m, p.z_m);
    ASSERT_LT((p_base[i] - direct).norm(), 1e-12) << i << " t " << p.t_s;
  }
  EXPECT_GT(expected_fallback, 0u);
  EXPECT_EQ(fallback, expected_fallback);
}

// DeskewScan = the carrier's motion (a constant twist, known in closed form) after the rotary transform, into
// ScanPoints (float positions: 1e-5 m at these < 10 m ranges), with both fallback counts.
TEST(DeskewScan, EqualsPlainRotaryThenConstantTwist) {
  RigCalib calib = CalibWithEncoder(16384);
  calib.T_base_motor = MakePose({0.1, 0, 0.2}, Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY())));
  calib.T_rotor_lidar = MakePose({0, 0.02, 0.08}, Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX())));
  RotorAngleInterpolator rotor(calib);
  std::vector<std::pair<double, double>> samples;
  for (int i = 0; i <= 90; ++i) {  // encoder over 1.00 .. 1.09 s only: later points fall back
    const double t = 1.0 + 1e-3 * i, theta = 2.6 * t;
    const uint32_t count = CountOf(theta, 16384);
    rotor.Add({t, count});
    const double decoded = calib.EncoderAngle(count);
    samples.emplace_back(t, decoded + 2 * M_PI * std::round((theta - decoded) / (2 * M_PI)));
  }
  Pose3 T_start_end = Pose3::Identity();
  T_start_end.linear() = ExpSO3(Eigen::Vector3d(0.02, -0.01, 0.1));
  T_start_end.translation() = Eigen::Vector3d(0.12, 0.01, -0.02);
  const MotionTable table = ConstantTwistTable(T_start_end, 1.0, 1.1, 10);
  LidarScan scan;
  for (int i = 0; i < 500; ++i) {
    LidarPoint p;
    p.x_m = 4.f * std::cos(0.1f * i), p.y_m = 4.f * std::sin(0.1f * i), p.z_m = 0.3f;
    p.t_s = 1.0 + 0.11 * i / 499.0;  // the last ~1/11 lies past the table and the encoder
    scan.points.push_back(p);
  }
  std::vector<ScanPoint> out;
  const DeskewCounts counts = DeskewScan(rotor, table, scan, &out);
  ASSERT_EQ(out.size(), scan.points.size());
  size_t expected_fallback = 0, expected_outside = 0;
  for (size_t i = 0; i < out.size(); ++i) {
    const LidarPoint& p = scan.points[i];
    bool fallback = false;
    const double angle = PlainAngle(samples, calib.motor_speed_radps, p.t_s, &fallback);
    const double s = std::min((p.t_s - 1.0) / 0.1, 1.0);
    Pose3 T = Pose3::Identity();
    T.linear() = ExpSO3(s * LogSO3(T_start_end.linear()));
    T.translation() = s * T_start_end.translation();
    const Eigen::Vector3d expected = T * calib.T_base_lidar(angle) * Eigen::Vector3d(p.x_m, p.y_m, p.z_m);
    ASSERT_LT((out[i].p_base.cast<double>() - expected).norm(), 1e-5) << i;
    EXPECT_EQ(out[i].t_s, p.t_s);
    expected_fallback += fallback;
    expected_outside += p.t_s > 1.1;
  }
  EXPECT_GT(expected_fallback, 0u);
  EXPECT_EQ(counts.rotor_fallback, expected_fallback);
  EXPECT_EQ(counts.motion_extrapolated, expected_outside);
}

}  // namespace
}  // namespace rotolidar
