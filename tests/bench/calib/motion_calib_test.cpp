// The motion stage's bookkeeping (bench/calib/motion_calib.hpp, calib_output.hpp): how its corrections enter
// calib.yaml, how the twin's truth counts the sensor clocks, what calibration.json records, and its options'
// validation. The stage's accuracy on the twin is MotionCalibrationScenario's (tests/scenario/).
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include "bench/calib/calib_output.hpp"
#include "bench/calib/motion_calib.hpp"
#include "core/io/calib_yaml.hpp"
#include "sim/sim_config.hpp"
#include "sim/truth/clock_truth.hpp"

namespace rotolidar::bench {
namespace {

std::string FreshDir(const std::string& name) {
  const std::string dir = (std::filesystem::temp_directory_path() / name).string();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir + "/truth");
  return dir;
}

TEST(MotionCalib, CorrectionsAddToTheCalibrationAndCompareBack) {
  RigCalib calib = sim::DefaultRigCalib();
  calib.encoder.zero_offset_rad = 0.01;
  calib.imu_time_offset_s = 0.002;
  MotionCalibResult r;
  r.encoder_zero_change_rad = -0.004;
  r.imu_time_offset_change_s = 0.013;
  const RigCalib out = ApplyMotionCorrection(calib, r);
  EXPECT_DOUBLE_EQ(out.encoder.zero_offset_rad, 0.006);
  EXPECT_DOUBLE_EQ(out.imu_time_offset_s, 0.015);
  const CalibComparison c = CompareCalib(out, calib);
  EXPECT_DOUBLE_EQ(c.encoder_zero_rad, -0.004);
  EXPECT_DOUBLE_EQ(c.imu_time_offset_s, 0.013);
  EXPECT_EQ(c.lever_m.norm(), 0.0);
}

TEST(MotionCalib, TwinTruthCountsTheEncoderLagAsAZeroAndTheImuClockAsItsOffset) {
  const std::string dir = FreshDir("rotolidar_motion_calib_truth");
  RigCalib truth = sim::DefaultRigCalib();
  truth.encoder.zero_offset_rad = 0.01;
  truth.motor_speed_radps = 2.6;
  ASSERT_TRUE(SaveCalibYaml(dir + "/truth/calib_true.yaml", truth).ok);
  RigCalib loaded;
  ASSERT_TRUE(LoadTwinTruth(dir, 10.0, &loaded).ok);  // no clocks.yaml: calib_true.yaml as it is
  EXPECT_DOUBLE_EQ(loaded.encoder.zero_offset_rad, 0.01);
  EXPECT_DOUBLE_EQ(loaded.imu_time_offset_s, 0.0);

  sim::ClockTruth clocks;
  clocks.encoder = {0.002, 50.0};  // stamp = t + 2 ms + 50 ppm t: 2.5 ms late at t = 10 s
  clocks.imu = {0.015, 20.0};      // 15.2 ms late at t = 10 s
  ASSERT_TRUE(sim::WriteClockTruth(dir, clocks).ok);
  ASSERT_TRUE(LoadTwinTruth(dir, 10.0, &loaded).ok);
  // A late encoder reads the angle of 2.5 ms earlier: every angle 2.6 * 2.5e-3 rad small, as a zero that large.
  EXPECT_NEAR(loaded.encoder.zero_offset_rad, 0.01 - 2.6 * 0.0025, 1e-12);
  EXPECT_NEAR(loaded.imu_time_offset_s, 0.0152, 1e-12);
  std::filesystem::remove_all(dir);
  EXPECT_FALSE(LoadTwinTruth(dir, 10.0, &loaded).ok);  // no calib_true.yaml
}

TEST(MotionCalib, CalibrationJsonRecordsTheStageOrWhyItDidNotRun) {
  const std::string dir = FreshDir("rotolidar_motion_calib_json");
  CalibrationReport rep;
  rep.input = rep.output = sim::DefaultRigCalib();
  rep.motion_note = "only 1.3 s of IMU data after the static span";
  ASSERT_TRUE(WriteCalibrationJson(dir + "/a.json", rep).ok);
  nlohmann::json j = nlohmann::json::parse(std::ifstream(dir + "/a.json"));
  EXPECT_FALSE(j.at("motion").at("ran").get<bool>());
  EXPECT_EQ(j.at("motion").at("note").get<std::string>(), rep.motion_note);

  rep.motion_ran = true;
  rep.motion.encoder_zero_change_rad = -0.0081;
  rep.motion.imu_time_offset_change_s = 0.0153;
  rep.motion.settled = true;
  rep.output = ApplyMotionCorrection(rep.input, rep.motion);
  ASSERT_TRUE(WriteCalibrationJson(dir + "/b.json", rep).ok);
  j = nlohmann::json::parse(std::ifstream(dir + "/b.json"));
  EXPECT_TRUE(j.at("motion").at("ran").get<bool>());
  EXPECT_TRUE(j.at("motion").at("settled").get<bool>());
  EXPECT_DOUBLE_EQ(j.at("motion").at("encoder_zero_change_rad").get<double>(), -0.0081);
  EXPECT_DOUBLE_EQ(j.at("output").at("imu_time_offset_s").get<double>(), 0.0153);
  EXPECT_DOUBLE_EQ(j.at("change").at("imu_time_offset_s").get<double>(), 0.0153);
  std::filesystem::remove_all(dir);
}

TEST(MotionCalib, RejectsOptionsItCannotRunWith) {
  std::string why;
  MotionCalibOptions o;
  EXPECT_TRUE(o.Validate(&why)) << why;
  o.estimator.use_imu = false;
  EXPECT_FALSE(o.Validate(&why));
  EXPECT_NE(why.find("use_imu"), std::string::npos) << why;
  o = MotionCalibOptions{};
  o.min_motion_s = 0.0;
  EXPECT_FALSE(o.Validate(&why));
  EXPECT_NE(why.find("min_motion_s"), std::string::npos) << why;
}

}  // namespace
}  // namespace rotolidar::bench
