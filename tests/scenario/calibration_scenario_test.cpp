// `rotolidar calibrate`'s method on the twin: the rig stands still in the box room while the rotor turns, with
// the `typical` realism (calibration errors drawn per seed, axis wobble, rotor vibration, clock offsets, the
// VLP-16's range physics). The lever arm across the rotor axis and the tilt about rotor x and y must come back
// from calib.yaml's believed values to the true ones (SimConfig::TrueCalib(), = truth/calib_true.yaml).
//
// Measured (docs/calibration.md, "Measured accuracy"; `rotolidar calibrate REC --out DIR` on the same recordings
// prints the same numbers), estimate - truth per seed, input -> estimate:
//   seed 1: lever x +0.32 -> -0.05, y +0.61 -> -0.12 mm; tilt x +0.0747 -> +0.0064, y -0.0540 -> +0.0048 deg
//   seed 2: lever x -0.34 -> +0.21, y -2.37 -> +0.30 mm; tilt x -0.0562 -> +0.0036, y +0.3007 -> -0.0023 deg
//   seed 3: lever x +3.39 -> +0.15, y -2.28 -> +0.11 mm; tilt x +0.0972 -> +0.0033, y +0.1900 -> -0.0078 deg
//   seed 4: lever x +0.33 -> -0.30, y +0.07 -> +0.03 mm; tilt x -0.0696 -> -0.0020, y +0.1052 -> -0.0014 deg
//   seed 5: lever x +1.40 -> +0.05, y +0.79 -> +0.02 mm; tilt x +0.0449 -> +0.0040, y +0.1255 -> +0.0013 deg
// Worst 0.30 mm and 0.0078 deg (formal sigmas 0.13-0.19 mm, 0.0025-0.0043 deg): the bounds below are the goal
// (2 mm, 0.05 deg), about 6x the worst measured.
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>

#include "bench/calib/calib_data.hpp"
#include "bench/calib/calib_output.hpp"
#include "bench/calib/rotor_calib.hpp"
#include "core/io/recording.hpp"
#include "tests/scenario/scenario_sim.hpp"

namespace rotolidar::bench {
namespace {

constexpr double kDeg = M_PI / 180.0;

/// Typical realism, the box room, handheld at rest for 4 s at (0.5, -0.5) while the rotor turns, then walking
/// (so that the static-span detector has an end to find).
sim::SimConfig StaticStart(uint64_t seed) {
  return test_util::TypicalBoxRoomWalk(seed, 5.5, {{0.5, -0.5, 4.0}, {2.5, -0.5, 0.0}});
}

void CalibrateSeed(uint64_t seed) {
  const sim::SimConfig config = StaticStart(seed);
  const std::string dir =
      test_util::SimulateFresh(config, "rotolidar_calibration_scenario_" + std::to_string(seed));
  ASSERT_FALSE(::testing::Test::HasFailure());
  Recording rec;
  ASSERT_TRUE(LoadRecording(dir + "/recording", &rec).ok);
  TimeSpan span;
  const Status detected = DetectStaticSpan(rec.imu, StaticSpanOptions{}, &span);
  ASSERT_TRUE(detected.ok) << detected.message;
  EXPECT_GT(span.t_end_s, 3.5);  // still for 4 s; the walk starts slowly (a 2 s kernel) and is seen within 0.5 s
  EXPECT_LE(span.t_end_s, 4.3);
  std::vector<RotorPoint> points;
  ASSERT_TRUE(LoadRotorPoints(rec, rec.calib, span, RotorPointOptions{}, &points).ok);
  RotorCalibResult result;
  const Status s = CalibrateRotor(points, rec.calib, RotorCalibOptions{}, &result);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_TRUE(result.converged);
  const RigCalib truth = config.TrueCalib();
  const CalibComparison before = CompareCalib(rec.calib, truth);
  const CalibComparison after = CompareCalib(ApplyCorrection(rec.calib, result.correction), truth);
  std::printf("seed %llu: lever x %+.2f -> %+.2f mm, y %+.2f -> %+.2f mm; tilt x %+.3f -> %+.3f deg, y %+.3f -> "
              "%+.3f deg\n", (unsigned long long)seed, 1e3 * before.lever_m.x(), 1e3 * after.lever_m.x(),
              1e3 * before.lever_m.y(), 1e3 * after.lever_m.y(), before.tilt_rad.x() / kDeg,
              after.tilt_rad.x() / kDeg, before.tilt_rad.y() / kDeg, after.tilt_rad.y() / kDeg);
  EXPECT_LT(std::abs(after.lever_m.x()), 0.002);
  EXPECT_LT(std::abs(after.lever_m.y()), 0.002);
  EXPECT_LT(std::abs(after.tilt_rad.x()), 0.05 * kDeg);
  EXPECT_LT(std::abs(after.tilt_rad.y()), 0.05 * kDeg);
  std::filesystem::remove_all(dir);
}

TEST(CalibrationScenario, RecoversLeverArmAndTiltSeed1) { CalibrateSeed(1); }
TEST(CalibrationScenario, RecoversLeverArmAndTiltSeed2) { CalibrateSeed(2); }
TEST(CalibrationScenario, RecoversLeverArmAndTiltSeed3) { CalibrateSeed(3); }
TEST(CalibrationScenario, RecoversLeverArmAndTiltSeed4) { CalibrateSeed(4); }
TEST(CalibrationScenario, RecoversLeverArmAndTiltSeed5) { CalibrateSeed(5); }

}  // namespace
}  // namespace rotolidar::bench
