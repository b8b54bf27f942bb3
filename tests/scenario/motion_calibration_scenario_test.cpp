// `rotolidar calibrate`'s two stages on the twin, as the command runs them: the static stage (lever arm and tilt)
// over the first seconds, then the motion stage (encoder zero and LiDAR-IMU time offset, bench/calib/
// motion_calib.hpp) over a loop walk through the box room. `typical` realism (its drawn encoder zero error, its
// clocks), with the IMU clock 15 ms late and the encoder clock 3 ms late on top, so that both corrections are far
// larger than what the stage may leave. The truth is the one the map needs (LoadTwinTruth: the encoder's lag
// counts as an encoder zero of the rotor speed times the lag). The written calibration must then make the core's
// default run (no online offsets) better than the static stage's calibration does.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "bench/calib/calib_data.hpp"
#include "bench/calib/calib_output.hpp"
#include "bench/calib/motion_calib.hpp"
#include "bench/calib/rotor_calib.hpp"
#include "bench/run/slam_run.hpp"
#include "bench/run/truth_eval.hpp"
#include "core/io/recording.hpp"
#include "tests/scenario/scenario_sim.hpp"

namespace rotolidar::bench {
namespace {

constexpr double kDeg = M_PI / 180.0;

/// Still for 4 s at (0.5, -0.5) while the rotor turns, then one loop around the room's middle (about 18 m, turns
/// of 90 deg at every corner).
sim::SimConfig StillThenLoop(uint64_t seed) {
  sim::SimConfig config = test_util::TypicalBoxRoomWalk(
      seed, 24.0, {{0.5, -0.5, 4.0}, {3.0, -0.5, 0.0}, {3.0, 0.6, 0.0}, {-3.0, 0.6, 0.0}, {-3.0, -2.6, 0.0},
                   {0.5, -2.6, 0.0}, {0.5, -0.5, 0.0}});
  config.imu.errors.imu_clock_offset_s = 0.015;
  config.clocks.encoder_offset_s = 0.003;
  return config;
}

/// ATE RMSE [m] of the core's default run over the recording with `calib` instead of its calib.yaml.
double AteWith(const std::string& rec, const RigCalib& calib, const std::string& out) {
  SlamRunOptions options;
  options.calib = &calib;
  SlamRunResult run;
  const Status slam = RunSlam(rec, EstimatorConfig{}, out, &run, options);
  EXPECT_TRUE(slam.ok) << slam.message;
  EvalResult ape;
  const Status eval = EvaluateAgainstTruth(rec, run.trajectory, &ape);
  EXPECT_TRUE(eval.ok) << eval.message;
  return ape.stats.rmse;
}

TEST(MotionCalibrationScenario, FindsTheEncoderZeroAndTheImuTimeOffset) {
  const std::string dir = test_util::SimulateFresh(StillThenLoop(1), "rotolidar_motion_calibration_scenario");
  ASSERT_FALSE(::testing::Test::HasFailure());
  Recording rec;
  ASSERT_TRUE(LoadRecording(dir + "/recording", &rec).ok);
  TimeSpan span;
  ASSERT_TRUE(DetectStaticSpan(rec.imu, StaticSpanOptions{}, &span).ok);
  std::vector<RotorPoint> points;
  ASSERT_TRUE(LoadRotorPoints(rec, rec.calib, span, RotorPointOptions{}, &points).ok);
  RotorCalibResult rotor;
  ASSERT_TRUE(CalibrateRotor(points, rec.calib, RotorCalibOptions{}, &rotor).ok);
  const RigCalib static_out = ApplyCorrection(rec.calib, rotor.correction);

  MotionCalibResult motion;
  const Status s = CalibrateMotion(rec.dir, static_out, span.t_end_s, MotionCalibOptions{}, dir + "/motion", &motion);
  ASSERT_TRUE(s.ok) << s.message;
  RigCalib truth;
  ASSERT_TRUE(LoadTwinTruth(rec.dir, motion.t_end_s, &truth).ok);
  const CalibComparison before = CompareCalib(rec.calib, truth);
  const RigCalib motion_out = ApplyMotionCorrection(static_out, motion);
  const CalibComparison after = CompareCalib(motion_out, truth);
  const double ate_static = AteWith(rec.dir, static_out, dir + "/slam_static");
  const double ate_motion = AteWith(rec.dir, motion_out, dir + "/slam_motion");
  std::printf("[measured] motion %.1f..%.1f s, %zu scans, path %.1f m, rotation %.0f deg; encoder zero %+.4f -> "
              "%+.4f deg (spread %.4f), IMU time offset %+.2f -> %+.2f ms (spread %.2f); ATE %.4f m static stage, "
              "%.4f m both\n", motion.t_start_s, motion.t_end_s, motion.scans, motion.path_length_m,
              motion.rotation_rad / kDeg, before.encoder_zero_rad / kDeg, after.encoder_zero_rad / kDeg, motion.encoder_zero_spread_rad / kDeg,
              1e3 * before.imu_time_offset_s, 1e3 * after.imu_time_offset_s, 1e3 * motion.imu_time_offset_spread_s,
              ate_static, ate_motion);
  // Measured (seed 1): encoder zero +0.565 -> -0.015 deg (spread 0.087 deg), IMU time offset -15.48 -> +0.55 ms
  // (spread 0.37 ms), ATE 0.0225 -> 0.0075 m. Seeds 1-5 of the same run through `rotolidar calibrate`
  // (docs/calibration.md, "Motion stage"): encoder zero within 0.333 deg, IMU time offset +0.45..+0.97 ms, spreads
  // at most 0.087 deg and 0.48 ms, the ATE ratio 0.32-0.35. Bounds:
  // - the IMU time offset within 2 ms (2x the worst of 15.5 ms injected);
  // - the encoder zero within 0.35 deg: the window aligns the LiDAR with the IMU, whose axes the twin misaligns by
  //   2 mrad per axis and whose mount it rotates by 0.1 deg (neither is in this truth); with the IMU's
  //   misalignment and scale errors off, the five seeds stay within 0.13 deg. A sign error would leave 1.1 deg;
  // - the ATE with the written calibration at most 0.6x the static stage's (worst measured 0.35x).
  EXPECT_TRUE(motion.settled);
  EXPECT_GT(motion.path_length_m, 15.0);
  EXPECT_LT(std::abs(after.encoder_zero_rad), 0.35 * kDeg);
  EXPECT_LT(std::abs(after.imu_time_offset_s), 0.002);
  EXPECT_LT(ate_motion, 0.6 * ate_static);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rotolidar::bench
