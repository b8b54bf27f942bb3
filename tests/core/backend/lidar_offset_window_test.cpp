// The window's offset blocks. Rotor offset: LiDAR poses measured through a scan turned about the motor axis (an
// encoder zero error or a drifting encoder clock) are explained, the offset is found from the IMU, and removing
// the estimate from later scans (as the Estimator does) converges to the true offset. IMU time offset: LiDAR poses
// taken later than the IMU states say (late IMU stamps) are explained the same way.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "tests/core/backend/window_test_sim.hpp"

namespace rotolidar {
namespace {

using namespace window_test;

struct OffsetRun {
  double final_offset = 0.0;            ///< the window's estimate at the end [rad or s]
  double rms_rotation_error_rad = 0.0;  ///< latest state's attitude against the truth, second half
  double rms_position_error_m = 0.0;
};

constexpr int kStates = 150;  // 15 s of the analytic motion

/// Runs kStates states through `window`: measure(k, applied) is state k's LiDAR measurement when the Estimator has
/// already removed `applied` (estimate() after the previous state), as it does from encoder angles and IMU stamps.
template <typename Measure, typename Estimate>
OffsetRun Drive(SlidingWindow& window, const std::vector<ImuSample>& imu, Measure measure, Estimate estimate) {
  EXPECT_TRUE(window.Initialize(0.0, InitialGuess(), measure(0, 0.0)).ok);
  OffsetRun out;
  double sum_r2 = 0.0, sum_p2 = 0.0;
  int n = 0;
  for (int k = 1; k < kStates; ++k) {
    const double applied = estimate();
    const Status st =
        window.AddState(StateTime(k), Preintegrate(imu, k - 1, window.latest_state()), measure(k, applied));
    EXPECT_TRUE(st.ok) << st.message;
    window.Optimize();
    if (k < kStates / 2) continue;
    const NavState x = window.latest_state(), truth = Motion::State(StateTime(k));
    sum_r2 += LogSO3(x.R_world_imu * truth.R_world_imu.transpose()).squaredNorm();
    sum_p2 += (x.p_world_m - truth.p_world_m).squaredNorm();
    ++n;
  }
  out.final_offset = estimate();
  out.rms_rotation_error_rad = std::sqrt(sum_r2 / n);
  out.rms_position_error_m = std::sqrt(sum_p2 / n);
  return out;
}

/// Prints the three runs of a test: the offset estimated, the offset ignored, and no offset (estimated).
void PrintMeasured(const char* what, const char* unit, double truth, const OffsetRun& estimated,
                   const OffsetRun& ignored, const OffsetRun& none) {
  std::printf("[measured] %s %.4f %s: estimated %.5f %s; attitude rms %.4f rad (ignored: %.4f), position rms %.4f m "
              "(ignored: %.4f); without an offset the estimate is %.5f %s\n",
              what, truth, unit, estimated.final_offset, unit, estimated.rms_rotation_error_rad,
              ignored.rms_rotation_error_rad, estimated.rms_position_error_m, ignored.rms_position_error_m,
              none.final_offset, unit);
}

/// 15 s of the analytic motion; each LiDAR measurement is the truth turned by B(phi_true - applied), applied = the
/// window's estimate after the previous state (0 when `estimate` is off).
OffsetRun RunWithOffset(double phi_true_rad, bool estimate) {
  SlidingWindowConfig config;
  config.gravity_world_mps2 = kGravity;
  config.estimate_rotor_offset = estimate;
  // A horizontal motor axis (the default rig's) 10 cm from the IMU.
  config.motor_in_imu.axis = Eigen::Vector3d::UnitY();
  config.motor_in_imu.origin_m = Eigen::Vector3d(0.05, 0.0, 0.1);
  SlidingWindow window(config);
  const std::vector<ImuSample> imu = MakeImu(StateTime(kStates) + 0.1, true, 7);
  RandomStream rng(8, "lidar_offset_window_test.lidar");
  auto measure = [&](int k, double applied) {
    LidarPoseMeasurement m = MakeLidar(StateTime(k), rng);
    m.T_world_imu = m.T_world_imu * config.motor_in_imu.B(phi_true_rad - applied);
    m.rotor_offset_applied_rad = applied;
    return m;
  };
  return Drive(window, imu, measure, [&] { return window.rotor_offset_rad(); });
}

TEST(RotorOffsetWindow, FindsTheOffsetAndKeepsTheAttitude) {
  constexpr double kPhi = 0.05;  // 2.9 deg: 19 ms of encoder clock at 2.6 rad/s
  const OffsetRun estimated = RunWithOffset(kPhi, true);
  const OffsetRun ignored = RunWithOffset(kPhi, false);
  const OffsetRun none = RunWithOffset(0.0, true);
  PrintMeasured("rotor offset", "rad", kPhi, estimated, ignored, none);
  // Measured: 0.04915 rad (0.85 mrad off), -0.82 mrad without an offset; attitude rms 2.1 mrad against 41.2 mrad
  // when the offset is ignored (the window then splits it between the LiDAR and the gyro). Bounds: a tenth of the
  // offset, and a quarter of the ignored attitude error.
  EXPECT_NEAR(estimated.final_offset, kPhi, 0.005);
  EXPECT_NEAR(none.final_offset, 0.0, 0.005);
  EXPECT_LT(estimated.rms_rotation_error_rad, 0.25 * ignored.rms_rotation_error_rad);
}

/// 15 s of the analytic motion with the IMU's stamps td_true late: after the Estimator's shift by the estimate
/// `applied`, state k (IMU time t_k) is the truth at t_k while the LiDAR saw the truth at t_k + td_true - applied.
OffsetRun RunWithTimeOffset(double td_true_s, bool estimate) {
  SlidingWindowConfig config;
  config.gravity_world_mps2 = kGravity;
  config.estimate_time_offset = estimate;
  SlidingWindow window(config);
  const std::vector<ImuSample> imu = MakeImu(StateTime(kStates) + 0.5, true, 9);
  RandomStream rng(10, "lidar_offset_window_test.time");
  auto measure = [&](int k, double applied) {
    LidarPoseMeasurement m = MakeLidar(StateTime(k) + td_true_s - applied, rng);
    m.time_offset_applied_s = applied;
    const Eigen::Vector3d bg = window.initialized() ? window.latest_state().bias_gyro_radps : Eigen::Vector3d::Zero();
    m.angular_velocity_imu_radps = imu[size_t(k * kSamplesPerState)].gyro_radps - bg;
    return m;
  };
  return Drive(window, imu, measure, [&] { return window.time_offset_s(); });
}

TEST(TimeOffsetWindow, FindsTheImuTimeOffsetAndKeepsThePose) {
  constexpr double kTd = 0.03;  // 30 ms: a 20 ppm IMU clock after 25 min
  const OffsetRun estimated = RunWithTimeOffset(kTd, true);
  const OffsetRun ignored = RunWithTimeOffset(kTd, false);
  const OffsetRun none = RunWithTimeOffset(0.0, true);
  PrintMeasured("IMU time offset", "s", kTd, estimated, ignored, none);
  // Measured: 0.02914 s (0.86 ms off), -0.46 ms without an offset; position rms 16.6 mm against 45.1 mm when the
  // offset is ignored (attitude 0.9 against 12.5 mrad). Bounds: a tenth of the offset, and half the ignored
  // position error (the LiDAR noise, 2 cm per axis, is most of what remains).
  EXPECT_NEAR(estimated.final_offset, kTd, 0.003);
  EXPECT_NEAR(none.final_offset, 0.0, 0.003);
  EXPECT_LT(estimated.rms_position_error_m, 0.5 * ignored.rms_position_error_m);
}

}  // namespace
}  // namespace rotolidar
