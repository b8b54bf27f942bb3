// The rotor calibration on synthetic data with a known miscalibration: a rig turning inside a box room (rays
// intersected with its six walls and a tilted panel), points taken with the true T_rotor_lidar and given the
// believed one. Also the residual's geometry against RigCalib, the static-span detector and the span parser.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include "bench/calib/calib_data.hpp"
#include "bench/calib/calib_output.hpp"
#include "bench/calib/rotor_calib.hpp"
#include "core/types/geometry.hpp"
#include "core/util/rng.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::bench {
namespace {

constexpr double kDeg = M_PI / 180.0;

/// Distance along the ray (origin o, unit direction d, base frame) to the box room [-4,4]x[-3,3]x[-1.3,1.7] or a
/// panel tilted 30 deg (the plane x + 0.5 z = 3) when that is nearer.
double CastRoom(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const Eigen::Vector3d lo(-4, -3, -1.3), hi(4, 3, 1.7);
  double t = 1e9;
  for (int k = 0; k < 3; ++k)
    if (std::abs(d[k]) > 1e-9) t = std::min(t, ((d[k] > 0 ? hi[k] : lo[k]) - o[k]) / d[k]);
  const Eigen::Vector3d n = Eigen::Vector3d(1, 0, 0.5).normalized();
  const double dn = n.dot(d);
  if (dn > 1e-6) {
    const double tp = (3.0 / Eigen::Vector3d(1, 0, 0.5).norm() - n.dot(o)) / dn;
    const Eigen::Vector3d hit = o + tp * d;
    if (tp > 0 && tp < t && std::abs(hit.y()) < 2.0 && hit.z() > -1.0 && hit.z() < 1.0) t = tp;
  }
  return t;
}

/// Points of a rig with calibration `truth` over two rotor revolutions; theta as the believed calibration's
/// encoder reads it (true angle minus the zero error), range noise sigma_m.
std::vector<RotorPoint> SyntheticRoom(const RigCalib& truth, double zero_error_rad, double sigma_m) {
  RandomStream rng(7, "calib.synthetic_room");
  std::vector<RotorPoint> points;
  const LidarIntrinsics lidar;
  for (int i = 0; i < 480; ++i) {
    const double theta = 4.0 * M_PI * i / 480.0;
    const Pose3 T = truth.T_base_lidar(theta);
    for (int a = 0; a < 72; ++a) {
      const double az = 2.0 * M_PI * (a + 0.37 * i) / 72.0;
      for (int l = 0; l < 16; ++l) {
        const double el = lidar.elevation_deg[l] * kDeg;
        const Eigen::Vector3d d_lidar(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
        const double range = CastRoom(T.translation(), T.linear() * d_lidar) + rng.Normal(0.0, sigma_m);
        if (range < 1.0) continue;
        points.push_back({(range * d_lidar).cast<float>(), theta - zero_error_rad, 0.0, 2.6});
      }
    }
  }
  return points;
}

/// The default rig with a known error: lever (2, -1.5, 3) mm, tilt (0.2, -0.15, 0) deg, encoder zero 0.1 deg.
RigCalib Believed(const RigCalib& truth) {
  RotorCalibParams e;
  e.lever_m = {0.002, -0.0015, 0.003};
  e.tilt_rad = {0.2 * kDeg, -0.15 * kDeg, 0.0};
  e.encoder_zero_rad = 0.1 * kDeg;
  return ApplyCorrection(truth, e);
}

TEST(RotorCalib, MotorPointMatchesRigCalibChain) {
  const RigCalib calib = sim::DefaultRigCalib();
  RotorCalibParams d;
  d.lever_m = {0.01, -0.02, 0.03};
  d.tilt_rad = {0.01, 0.02, -0.03};
  d.encoder_zero_rad = 0.05;
  d.time_offset_s = 0.01;  // the encoder's angle 10 ms later: + 2.0 rad/s * 0.01 s
  const RigCalib corrected = ApplyCorrection(calib, d);
  EXPECT_DOUBLE_EQ(corrected.lidar_clock_offset_s, calib.lidar_clock_offset_s + 0.01);
  const RotorPoint p{Eigen::Vector3f(3.0f, -1.0f, 0.5f), 1.3, 0.0, 2.0};
  const std::vector<ResidualPoint> table = PrepareResidualPoints({p}, calib);
  const Eigen::Vector3d t = calib.T_rotor_lidar.translation();
  const double t0[3] = {t.x(), t.y(), t.z()};
  std::vector<float> xyz;
  MotorFramePoints(table, t0, d, &xyz);
  // theta' = theta - encoder_zero change: the corrected calibration's own chain.
  const Eigen::Vector3d expect = calib.T_base_motor.inverse() *
                                 corrected.T_base_lidar(p.theta_rad - d.encoder_zero_rad + 2.0 * 0.01) *
                                 p.p_lidar.cast<double>();
  EXPECT_LT((Eigen::Vector3f(&xyz[0]).cast<double>() - expect).norm(), 1e-5);
}

TEST(RotorCalib, CompareCalibInvertsApplyCorrection) {
  const RigCalib calib = sim::DefaultRigCalib();
  RotorCalibParams d;
  d.lever_m = {0.001, 0.002, -0.003};
  d.tilt_rad = {0.004, -0.005, 0.0};
  d.encoder_zero_rad = 0.006;
  const CalibComparison c = CompareCalib(ApplyCorrection(calib, d), calib);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(c.lever_m[k], d.lever_m[k], 1e-12);
    EXPECT_NEAR(c.tilt_rad[k], d.tilt_rad[k], 1e-9);
  }
  EXPECT_NEAR(c.encoder_zero_rad, 0.006, 1e-12);
}

TEST(RotorCalib, RecoversLeverAndTiltInASyntheticRoom) {
  const RigCalib truth = sim::DefaultRigCalib();
  const RigCalib believed = Believed(truth);
  const std::vector<RotorPoint> points = SyntheticRoom(truth, 0.1 * kDeg, 0.005);
  RotorCalibOptions options;
  options.max_queries = 8000;
  RotorCalibResult result;
  const Status s = CalibrateRotor(points, believed, options, &result);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_TRUE(result.converged);
  const CalibComparison before = CompareCalib(believed, truth);
  const CalibComparison after = CompareCalib(ApplyCorrection(believed, result.correction), truth);
  // Across the rotor axis the lever arm and the tilt come back; along it and about it they are held.
  EXPECT_LT(std::abs(after.lever_m.x()), 0.0005) << before.lever_m.x();
  EXPECT_LT(std::abs(after.lever_m.y()), 0.0005) << before.lever_m.y();
  EXPECT_LT(std::abs(after.tilt_rad.x()), 0.01 * kDeg) << before.tilt_rad.x();
  EXPECT_LT(std::abs(after.tilt_rad.y()), 0.01 * kDeg) << before.tilt_rad.y();
  EXPECT_DOUBLE_EQ(after.lever_m.z(), before.lever_m.z());
  for (int p : {kLeverX, kLeverY, kTiltX, kTiltY}) {
    EXPECT_TRUE(result.observability[p].observable) << CalibParamName(p);
    EXPECT_LT(result.observability[p].sigma, 1e-3) << CalibParamName(p);
  }
  for (int p : {kLeverZ, kTiltZ, kEncoderZero, kTimeOffset})  // time offset: an encoder zero at constant speed
    EXPECT_FALSE(result.observability[p].observable)
        << CalibParamName(p) << " " << result.observability[p].independence;
}

TEST(CalibOutput, WritesJsonAndPictures) {
  const RigCalib truth = sim::DefaultRigCalib();
  CalibrationReport rep;
  rep.input = Believed(truth);
  const std::vector<RotorPoint> points = SyntheticRoom(truth, 0.0, 0.005);
  rep.options.max_queries = 3000;
  ASSERT_TRUE(CalibrateRotor(points, rep.input, rep.options, &rep.result).ok);
  rep.output = ApplyCorrection(rep.input, rep.result.correction);
  rep.has_truth = true;
  rep.truth_after = CompareCalib(rep.output, truth);
  const std::string dir = (std::filesystem::temp_directory_path() / "rotolidar_calib_output_test").string();
  std::filesystem::create_directories(dir);
  ASSERT_TRUE(WriteCrispnessPicture(dir + "/before.svg", "before", points, rep.input, rep.options, RotorCalibParams{},
                                    &rep.median_abs_before_m).ok);
  ASSERT_TRUE(WriteCrispnessPicture(dir + "/after.svg", "after", points, rep.input, rep.options,
                                    rep.result.correction, &rep.median_abs_after_m).ok);
  EXPECT_LT(rep.median_abs_after_m, rep.median_abs_before_m);  // the map is crisper
  ASSERT_TRUE(WriteCalibrationJson(dir + "/calibration.json", rep).ok);
  std::ifstream f(dir + "/calibration.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_TRUE(j.at("converged").get<bool>());
  EXPECT_TRUE(j.at("parameters").at("lever_x_m").at("observable").get<bool>());
  EXPECT_FALSE(j.at("parameters").at("encoder_zero_rad").at("observable").get<bool>());
  EXPECT_NEAR(j.at("change").at("tilt_deg")[0].get<double>(), -0.2, 0.01);
  EXPECT_EQ(j.at("hessian").size(), std::size_t(kCalibParamCount));
  EXPECT_TRUE(j.contains("truth_error"));
  const std::uintmax_t svg_bytes = std::filesystem::file_size(dir + "/after.svg");
  EXPECT_GT(svg_bytes, 1000u);
  std::filesystem::remove_all(dir);
  EXPECT_FALSE(WriteCalibrationJson("/nonexistent_dir/calibration.json", rep).ok);
}

TEST(RotorCalib, RejectsBadOptions) {
  RotorCalibOptions o;
  o.sectors = 3;
  std::string why;
  EXPECT_FALSE(o.Validate(&why));
  EXPECT_NE(why.find("sectors"), std::string::npos);
  o = RotorCalibOptions();
  o.estimate.fill(false);
  EXPECT_FALSE(o.Validate(&why));
  RotorCalibResult result;
  EXPECT_FALSE(CalibrateRotor({}, sim::DefaultRigCalib(), RotorCalibOptions(), &result).ok);
}

TEST(StaticSpan, EndsWhereTheBaseStartsMoving) {
  std::vector<ImuSample> imu;
  for (int i = 0; i < 1200; ++i) {  // 200 Hz: still for 3 s (with a vibration line), then accelerating
    ImuSample s;
    s.t_s = i / 200.0;
    s.gyro_radps = Eigen::Vector3d(0.003, -0.002, 0.001 + 0.002 * std::sin(2 * M_PI * 20.7 * s.t_s));
    s.accel_mps2 = Eigen::Vector3d(0.05 * std::sin(2 * M_PI * 20.7 * s.t_s), 0.0, 9.81);
    if (s.t_s > 3.0) s.accel_mps2.x() += 0.8 * (s.t_s - 3.0), s.gyro_radps.z() += 0.2 * (s.t_s - 3.0);
    imu.push_back(s);
  }
  TimeSpan span;
  const Status s = DetectStaticSpan(imu, StaticSpanOptions{}, &span);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(span.t_start_s, 0.0);
  EXPECT_GT(span.t_end_s, 2.5);
  EXPECT_LE(span.t_end_s, 3.0);
  for (ImuSample& sample : imu) sample.gyro_radps.z() += 0.5 * sample.t_s;  // turning from the start
  EXPECT_FALSE(DetectStaticSpan(imu, StaticSpanOptions{}, &span).ok);
}

TEST(StaticSpan, ParsesAndRejectsSpans) {
  TimeSpan span;
  ASSERT_TRUE(ParseTimeSpan("0.5:4", &span).ok);
  EXPECT_DOUBLE_EQ(span.t_start_s, 0.5);
  EXPECT_DOUBLE_EQ(span.t_end_s, 4.0);
  for (const char* bad : {"", "4", "4:1", "a:2", "1:2x", "1:"}) {
    const Status s = ParseTimeSpan(bad, &span);
    EXPECT_FALSE(s.ok) << bad;
    EXPECT_NE(s.message.find("A:B"), std::string::npos);
  }
}

}  // namespace
}  // namespace rotolidar::bench
