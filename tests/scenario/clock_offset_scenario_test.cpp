// The window's online clock calibration on the twin: 10 s of the demo's run (box room, the default handheld loop,
// `typical` realism, seed 1, camera off) whose IMU clock is 20 ms late and whose encoder clock is 5 ms late
// (no drift), run with window.estimate_time_offset and estimate_rotor_offset. The IMU time offset must come out
// near the injected one, the rotor offset near the encoder's lag in rotor angle, and the ATE must not be worse
// than the same run without the estimates.
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "bench/run/slam_run.hpp"
#include "bench/run/truth_eval.hpp"
#include "core/io/calib_yaml.hpp"
#include "tests/scenario/scenario_sim.hpp"

namespace rotolidar::bench {
namespace {

constexpr double kImuOffsetS = 0.020;
constexpr double kEncoderOffsetS = 0.005;

struct OffsetRun {
  SlamRunResult slam;
  EvalResult ape;
};

OffsetRun RunWithOffsets(const std::string& rec, const std::string& out, bool estimate) {
  EstimatorConfig config;
  config.window.estimate_time_offset = estimate;
  config.window.estimate_rotor_offset = estimate;
  OffsetRun r;
  const Status slam = RunSlam(rec, config, out, &r.slam);
  EXPECT_TRUE(slam.ok) << slam.message;
  const Status eval = EvaluateAgainstTruth(rec, r.slam.trajectory, &r.ape);
  EXPECT_TRUE(eval.ok) << eval.message;
  return r;
}

TEST(ClockOffsetScenario, TheWindowFindsTheImuAndEncoderClockOffsets) {
  sim::SimConfig config = sim::PresetSimConfig(sim::Realism::kTypical);
  config.scene = "box_room";
  config.duration_s = 10.0;
  config.camera.enabled = false;
  config.imu.errors.imu_clock_offset_s = kImuOffsetS;
  config.imu.errors.imu_clock_drift_ppm = 0.0;
  config.clocks.encoder_offset_s = kEncoderOffsetS;
  config.clocks.encoder_drift_ppm = 0.0;
  const std::string dir = test_util::SimulateFresh(config, "rotolidar_clock_offset_scenario");
  ASSERT_FALSE(::testing::Test::HasFailure());
  const std::string rec = dir + "/recording";
  const OffsetRun estimated = RunWithOffsets(rec, dir + "/slam_estimated", true);
  const OffsetRun fixed = RunWithOffsets(rec, dir + "/slam_fixed", false);
  ASSERT_FALSE(estimated.slam.scans.empty());
  const ScanReport& last = estimated.slam.scans.back();
  // An encoder stamp late by dt reads the angle of dt earlier: at the rig's speed w the angles are w dt too
  // small, phi = -w dt.
  RigCalib calib;
  ASSERT_TRUE(LoadCalibYaml(rec + "/calib.yaml", &calib).ok);
  const double w = calib.motor_speed_radps;
  std::printf("[measured] IMU time offset %.2f ms (injected %.2f); rotor offset %.4f rad (expected %.4f); ATE "
              "%.4f m estimated, %.4f m fixed\n", 1e3 * last.imu_time_offset_s, 1e3 * kImuOffsetS,
              last.rotor_offset_rad, -w * kEncoderOffsetS, estimated.ape.stats.rmse, fixed.ape.stats.rmse);
  // Measured (seed 1): 21.71 ms, -0.0111 rad against -0.0130 rad expected. Ten seconds of a slow walk leave the
  // estimates 1.7 ms and 2-4.5 mrad off the truth (the 30 min walk of docs/estimator.md ends within 0.9 ms and
  // 1.0 mrad); the bounds are 1.5-3.5x those errors, far below the offsets themselves, so a wrong sign or a stuck
  // estimate fails.
  EXPECT_NEAR(last.imu_time_offset_s, kImuOffsetS, 0.006);
  EXPECT_NEAR(last.rotor_offset_rad, -w * kEncoderOffsetS, 0.007);
  // ATE estimated / fixed over seeds 1-6 (rotolidar sim with these offsets, rotolidar slam with the estimates on
  // and off): 0.0185/0.0174, 0.0161/0.0193, 0.0170/0.0191, 0.0149/0.0169, 0.0159/0.0171, 0.0187/0.0186 m. The
  // estimates help on 4 of 6 seeds and cost at most 6 % on one (this one): the bound is that spread plus a
  // margin; a stuck or wrong-signed estimate is what the bounds above catch.
  EXPECT_LT(estimated.ape.stats.rmse, 1.10 * fixed.ape.stats.rmse);
}

}  // namespace
}  // namespace rotolidar::bench
