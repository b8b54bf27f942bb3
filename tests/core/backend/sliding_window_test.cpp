// SlidingWindow on a synthetic trajectory: an analytic motion, IMU samples from it (constant injected biases, with
// and without Kalibr noise from seeded RandomStreams) and LiDAR pose measurements = truth + noise.
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include <ceres/types.h>
#include <gtest/gtest.h>

#include "core/backend/sliding_window.hpp"
#include "core/util/rng.hpp"
#include "window_test_sim.hpp"

namespace rotolidar {
namespace {
using namespace window_test;  // NOLINT: the synthetic data of window_test_sim.hpp

struct Errors {
  double pos_rms_m = 0, rot_rms_rad = 0, vel_rms_mps = 0;
};

/// RMS errors of states[from..] (state k + 1 at index k, as WindowRun stores them) against the truth.
Errors RmsErrors(const std::vector<NavState>& states, size_t from) {
  Errors e;
  for (size_t k = from; k < states.size(); ++k) {
    const NavState truth = Motion::State(StateTime(static_cast<int>(k) + 1));
    e.pos_rms_m += (states[k].p_world_m - truth.p_world_m).squaredNorm();
    e.rot_rms_rad += LogSO3(states[k].R_world_imu.transpose() * truth.R_world_imu).squaredNorm();
    e.vel_rms_mps += (states[k].v_world_mps - truth.v_world_mps).squaredNorm();
  }
  const double n = static_cast<double>(states.size() - from);
  e.pos_rms_m = std::sqrt(e.pos_rms_m / n);
  e.rot_rms_rad = std::sqrt(e.rot_rms_rad / n);
  e.vel_rms_mps = std::sqrt(e.vel_rms_mps / n);
  return e;
}

auto LidarEveryState(double noise_scale = 1.0) {
  return [noise_scale](int k, RandomStream& rng) -> std::optional<LidarPoseMeasurement> {
    return MakeLidar(StateTime(k), rng, noise_scale);
  };
}

/// Position error [m] of IMU-only dead reckoning from the true initial state with the biases taken as zero.
double ImuOnlyFinalPositionError(const std::vector<ImuSample>& imu, int num_states) {
  NavState dead = InitialGuess();
  for (int k = 0; k + 1 < num_states; ++k) dead = Preintegrate(imu, k, dead).Predict(dead, kGravity);
  return (dead.p_world_m - Motion::State(StateTime(num_states - 1)).p_world_m).norm();
}

/// The window with gravity held at kGravity (estimate_gravity = false): the tests below check the equations and
/// the marginalisation against data generated with exactly that gravity, where a free gravity direction only
/// trades against the accelerometer bias (SlidingWindow.GravityFollowsATiltingMap covers the estimated gravity).
SlidingWindowConfig FixedGravityConfig() {
  SlidingWindowConfig c;
  c.estimate_gravity = false;
  return c;
}

/// The window solved to convergence at every step (the default's 3 iterations suit a window already near its
/// optimum, as in the estimator; these tests also check that every solve converges).
SlidingWindowConfig ConvergingConfig() {
  SlidingWindowConfig c;
  c.max_iterations = 10;
  return c;
}

TEST(SlidingWindow, FusesBetterThanLidarOrImuAloneAndRecoversBiases) {
  constexpr int kStates = 80;  // 8 s
  for (const bool noisy_imu : {true, false}) {
    SCOPED_TRACE(noisy_imu ? "Kalibr-noise IMU" : "noise-free IMU");
    const std::vector<ImuSample> imu = MakeImu(8.0, noisy_imu, 11);
    SlidingWindow window{ConvergingConfig()};
    const WindowRun run = RunWindow(&window, imu, kStates, LidarEveryState());
    const Errors fused = RmsErrors(run.latest, 20), lidar = RmsErrors(run.lidar, 20);
    const double imu_only_m = ImuOnlyFinalPositionError(imu, kStates);
    const NavState est = window.latest_state();
    const double bg_err = (est.bias_gyro_radps - kBiasGyro).norm();
    const double ba_err = (est.bias_accel_mps2 - kBiasAccel).norm();
    std::printf("[measured] fused pos %.4f rot %.5f vel %.4f | lidar pos %.4f rot %.5f | imu-only %.2f | "
                "bg %.2e ba %.2e | %.1f iterations, %.2f ms per solve\n",
                fused.pos_rms_m, fused.rot_rms_rad, fused.vel_rms_mps, lidar.pos_rms_m, lidar.rot_rms_rad,
                imu_only_m, bg_err, ba_err, run.iterations / (kStates - 1.0), 1e3 * run.solve_time_s / (kStates - 1));
    // Measured over the LiDAR noise seeds 1-11 (noisy and noise-free IMU, 22 runs), RMS over states 21..79 of the
    //   latest-state (real-time) estimate: position 1.6-2.2 cm vs LiDAR-only 3.2-3.9 cm (3-axis RMS of 2 cm noise:
    //   3.46 expected), rotation 1.8-3.1 mrad vs 7.9-9.5 mrad, velocity 2.7-4.0 cm/s; IMU-only dead reckoning is
    //   off by 15.4 m at 7.9 s. Biases after 8 s: |bg error| 1.3e-4 to 5.6e-4 rad/s, |ba error| 5.1e-3 to
    //   3.5e-2 m/s^2 (median 1.6e-2: the accelerometer bias is only as good as the tilt, 5 mrad per scan).
    //   Bounds: the worst ratio plus ~15 % on position and rotation, 1.25x the worst velocity, ~1.7x on the biases.
    EXPECT_TRUE(run.all_converged);
    EXPECT_LT(fused.pos_rms_m, 0.7 * lidar.pos_rms_m);
    EXPECT_LT(fused.rot_rms_rad, 0.5 * lidar.rot_rms_rad);
    EXPECT_LT(fused.pos_rms_m, 0.01 * imu_only_m);
    EXPECT_LT(fused.vel_rms_mps, 0.05);
    EXPECT_LT(bg_err, 1e-3);
    EXPECT_LT(ba_err, 0.06);
  }
}

TEST(SlidingWindow, ExactDataRecoversBiasesAndRepropagates) {
  constexpr int kStates = 40;
  const std::vector<ImuSample> imu = MakeImu(4.0, false, 0);
  SlidingWindow window{FixedGravityConfig()};
  // Preintegrated at zero bias: the gyro bias (|bg| = 0.03 rad/s) exceeds the 0.01 repropagation threshold.
  const WindowRun run = RunWindow(&window, imu, kStates, LidarEveryState(0.0), true);
  const NavState est = window.latest_state(), truth = Motion::State(StateTime(kStates - 1));
  const double bg_err = (est.bias_gyro_radps - kBiasGyro).norm();
  const double ba_err = (est.bias_accel_mps2 - kBiasAccel).norm();
  const double pos_err = (est.p_world_m - truth.p_world_m).norm();
  const double vel_err = (est.v_world_mps - truth.v_world_mps).norm();
  std::printf("[measured] exact: repropagated %d bg %.2e ba %.2e pos %.2e vel %.2e\n", run.repropagated, bg_err, ba_err,
              pos_err, vel_err);
  // Exact data leave only the first-state prior's pull on the biases (prior information 2500 against ~2e6 from
  // 40 exact rotations: 0.03 rad/s * 2500 / 2e6 = 3.7e-5) and the 200 Hz midpoint discretisation. Measured:
  // bg 3.9e-5 rad/s, ba 3.7e-4 m/s^2, position 1.5e-4 m, velocity 3.5e-4 m/s; 43 re-integrations.
  EXPECT_GT(run.repropagated, 0);
  EXPECT_LT(bg_err, 1e-4);
  EXPECT_LT(ba_err, 1e-3);
  EXPECT_LT(pos_err, 1e-3);
  EXPECT_LT(vel_err, 1e-3);
}

/// Largest position difference [m], over all steps, between the window's oldest state (the one the marginalisation
/// prior, or the dropped state's absence, conditions directly) and the batch's estimate of the same state.
double MaxOldestStateGap(const WindowRun& run, const WindowRun& batch) {
  double worst = 0.0;
  for (size_t k = 0; k < run.windows.size(); ++k) {
    const WindowStateEstimate& oldest = run.windows[k].front();
    for (const WindowStateEstimate& b : batch.windows[k]) {
      if (b.t_s == oldest.t_s) worst = std::max(worst, (b.state.p_world_m - oldest.state.p_world_m).norm());
    }
  }
  return worst;
}

TEST(SlidingWindow, SchurMarginalizationTracksTheBatchSolutionWithoutJumps) {
  constexpr int kStates = 50;  // the 10-state window slides 40 times
  const std::vector<ImuSample> imu = MakeImu(5.0, true, 12);
  SlidingWindowConfig batch_config = FixedGravityConfig();
  batch_config.window_size = kStates + 1;  // never marginalises: the full batch (smoothing) solution
  const bool sparse = ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) ||
                      ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE);
  if (sparse) batch_config.linear_solver = ceres::SPARSE_NORMAL_CHOLESKY;  // a chain: sparse is O(n)
  SlidingWindowConfig drop_config = FixedGravityConfig();
  drop_config.marginalization = MarginalizationScheme::kDropOldest;
  SlidingWindow schur{FixedGravityConfig()}, batch{batch_config}, drop{drop_config};
  const WindowRun schur_run = RunWindow(&schur, imu, kStates, LidarEveryState());
  const WindowRun batch_run = RunWindow(&batch, imu, kStates, LidarEveryState());
  const WindowRun drop_run = RunWindow(&drop, imu, kStates, LidarEveryState());
  EXPECT_TRUE(schur_run.all_converged && batch_run.all_converged);
  EXPECT_EQ(schur.num_marginalized(), kStates - 10);
  EXPECT_EQ(batch.num_marginalized(), 0);
  // The latest state after every step, against the batch's latest state (the same data, nothing marginalised).
  double schur_pos = 0, schur_vel = 0, drop_pos = 0, drop_vel = 0;
  for (size_t k = 0; k < batch_run.latest.size(); ++k) {
    const NavState& b = batch_run.latest[k];
    schur_pos = std::max(schur_pos, (schur_run.latest[k].p_world_m - b.p_world_m).norm());
    schur_vel = std::max(schur_vel, (schur_run.latest[k].v_world_mps - b.v_world_mps).norm());
    drop_pos = std::max(drop_pos, (drop_run.latest[k].p_world_m - b.p_world_m).norm());
    drop_vel = std::max(drop_vel, (drop_run.latest[k].v_world_mps - b.v_world_mps).norm());
  }
  const NavState sb = schur.latest_state(), bb = batch.latest_state(), db = drop.latest_state();
  const double schur_ba = (sb.bias_accel_mps2 - bb.bias_accel_mps2).norm();
  const double drop_ba = (db.bias_accel_mps2 - bb.bias_accel_mps2).norm();
  const double schur_gap = MaxOldestStateGap(schur_run, batch_run), drop_gap = MaxOldestStateGap(drop_run, batch_run);
  std::printf("[measured] vs batch: schur pos %.2e vel %.2e ba %.2e gap %.2e | "
              "drop pos %.2e vel %.2e ba %.2e gap %.2e\n",
              schur_pos, schur_vel, schur_ba, schur_gap, drop_pos, drop_vel, drop_ba, drop_gap);
  // Measured: Schur vs batch, worst over the 49 steps, latest position 1.2e-5 m, velocity 3.0e-5 m/s, final accel
  // bias 3.4e-5 m/s^2, oldest state 4.5e-6 m (linearisation differences only, ~1e-3 of the LiDAR noise); dropping
  // the oldest state instead: 2.9e-2 m, 0.21 m/s, 0.21 m/s^2, 3.7e-2 m. Bounds ~5x the Schur values.
  EXPECT_LT(schur_pos, 1e-4);
  EXPECT_LT(schur_vel, 2e-4);
  EXPECT_LT(schur_ba, 2e-4);
  EXPECT_LT(schur_gap, 5e-5);
  EXPECT_GT(drop_pos, 3.0 * schur_pos);
  EXPECT_GT(drop_ba, 3.0 * schur_ba);
  EXPECT_GT(drop_gap, 3.0 * schur_gap);
}

TEST(SlidingWindow, DegenerateLidarAxisIsFilledByTheImu) {
  constexpr int kStates = 45, kDegenerateFrom = 30;  // 3 s to learn the biases, then 1.5 s degenerate along x
  const std::vector<ImuSample> imu = MakeImu(4.5, true, 13);
  // From kDegenerateFrom on the registration slides along world x (a corridor): its x is off by 0.5 m.
  auto corrupted = [](bool zero_x_information) {
    return [zero_x_information](int k, RandomStream& rng) -> std::optional<LidarPoseMeasurement> {
      LidarPoseMeasurement m = MakeLidar(StateTime(k), rng);
      if (k < kDegenerateFrom) return m;
      m.T_world_imu.translation().x() += 0.5;
      if (zero_x_information) m.information(0, 0) = 0.0;
      return m;
    };
  };
  SlidingWindow degenerate{FixedGravityConfig()}, trusting{FixedGravityConfig()};
  const WindowRun run = RunWindow(&degenerate, imu, kStates, corrupted(true));
  EXPECT_TRUE(run.all_converged);  // (the control fights a 25-sigma conflict and may hit the iteration cap)
  const WindowRun control = RunWindow(&trusting, imu, kStates, corrupted(false));
  double x_err = 0.0, yz_err = 0.0, control_x_err = 0.0;
  for (int k = kDegenerateFrom; k < kStates; ++k) {
    const NavState truth = Motion::State(StateTime(k));
    const Eigen::Vector3d e = run.latest[k - 1].p_world_m - truth.p_world_m;
    x_err = std::max(x_err, std::abs(e.x()));
    yz_err = std::max(yz_err, e.tail<2>().norm());
    control_x_err = std::max(control_x_err, std::abs(control.latest[k - 1].p_world_m.x() - truth.p_world_m.x()));
  }
  std::printf("[measured] degenerate: x %.4f yz %.4f | full-information control x %.4f\n", x_err, yz_err,
              control_x_err);
  // Measured: x follows the IMU to 4.3 cm over 1.5 s (velocity error ~2.5 cm/s * 1.5 s), y/z 1.7 cm; trusting the
  // corrupted x instead gives 0.62 m.
  EXPECT_LT(x_err, 0.08);
  EXPECT_LT(yz_err, 0.05);
  EXPECT_GT(control_x_err, 0.3);
}

/// A run where the LiDAR measurements are the truth in a world that tilts about y at tilt_rate_radps
/// (Ry(rate t): the map's roll/pitch drift; a fixed gravity then leaks g * tilt into world x), with no x
/// information from state degenerate_from on (a corridor along x). LiDAR noise 5 mm / 1.25 mrad per axis.
struct TiltOutcome {
  double x_err_m = 0;         ///< worst |x error| of the latest state over the degenerate stretch (tilted world)
  double gravity_err_rad = 0; ///< final gravity estimate vs the tilted world's gravity
};
TiltOutcome RunTiltingMap(double tilt_rate_radps, bool estimate_gravity, int num_states, int degenerate_from) {
  const std::vector<ImuSample> imu = MakeImu(num_states * 0.1, true, 14);
  auto tilt = [tilt_rate_radps](double t) { return Ry(tilt_rate_radps * t); };
  auto tilted_lidar = [&](int k, RandomStream& rng) -> std::optional<LidarPoseMeasurement> {
    LidarPoseMeasurement m = MakeLidar(StateTime(k), rng, 0.25);
    m.information *= 16.0;  // (1 / 0.25)^2
    Pose3 T_tilt = Pose3::Identity();
    T_tilt.linear() = tilt(StateTime(k));
    m.T_world_imu = T_tilt * m.T_world_imu;
    if (k >= degenerate_from) m.information(0, 0) = 0.0;
    return m;
  };
  SlidingWindowConfig config = ConvergingConfig();
  config.estimate_gravity = estimate_gravity;
  SlidingWindow window{config};
  const WindowRun r = RunWindow(&window, imu, num_states, tilted_lidar);
  EXPECT_TRUE(r.all_converged);
  TiltOutcome o;
  for (int k = degenerate_from; k < num_states; ++k) {
    const Eigen::Vector3d truth = tilt(StateTime(k)) * Motion::State(StateTime(k)).p_world_m;
    o.x_err_m = std::max(o.x_err_m, std::abs(r.latest[k - 1].p_world_m.x() - truth.x()));
  }
  const Eigen::Vector3d g_tilted = (tilt(StateTime(num_states - 1)) * kGravity).normalized();
  o.gravity_err_rad = std::acos(std::min(1.0, window.gravity_world_mps2().normalized().dot(g_tilted)));
  return o;
}

// With estimate_gravity the window's gravity follows the tilting world while x is observed, so only the tilt added
// during the degenerate stretch leaks into x; a fixed gravity leaks the whole tilt.
TEST(SlidingWindow, GravityFollowsATiltingMap) {
  constexpr int kStates = 100, kDegenerateFrom = 70;  // 7 s with full information, then 3 s degenerate along x
  constexpr double kTiltRate = 1e-3;                   // [rad/s]: 0.57 deg over 10 s (~3x the sim's map drift)
  const TiltOutcome estimated = RunTiltingMap(kTiltRate, true, kStates, kDegenerateFrom);
  const TiltOutcome fixed = RunTiltingMap(kTiltRate, false, kStates, kDegenerateFrom);
  const TiltOutcome tracked = RunTiltingMap(kTiltRate, true, kStates, kStates);  // full information throughout
  // The price of the free direction on a map that does not tilt: it wanders with the random walk.
  const TiltOutcome level = RunTiltingMap(0.0, true, kStates, kDegenerateFrom);
  const TiltOutcome level_fixed = RunTiltingMap(0.0, false, kStates, kDegenerateFrom);
  std::printf("[measured] tilting map: x error estimated gravity %.4f m, fixed %.4f m | final gravity vs tilted "
              "world %.2e rad (tilt %.2e) | level map: x error %.4f m (fixed %.4f), gravity %.2e rad\n",
              estimated.x_err_m, fixed.x_err_m, tracked.gravity_err_rad, kTiltRate * StateTime(kStates - 1),
              level.x_err_m, level_fixed.x_err_m, level.gravity_err_rad);
  // Measured: x error 2.2 cm vs 38 cm with the fixed gravity; gravity tracks ~55 % of the 9.9 mrad tilt (the
  // tilting world also rotates against the gyro, which the biases partly absorb). Level map: 5.7 cm vs 1.9 cm,
  // the estimate wanders 1.3 mrad.
  EXPECT_LT(estimated.x_err_m, 0.25 * fixed.x_err_m);
  EXPECT_LT(tracked.gravity_err_rad, 0.6 * kTiltRate * StateTime(kStates - 1));
  EXPECT_LT(level.x_err_m, 0.12);
  EXPECT_LT(level.gravity_err_rad, 4e-3);
}

TEST(SlidingWindow, PredictsFromTheLatestStateAndRejectsBadInput) {
  const std::vector<ImuSample> imu = MakeImu(0.3, false, 0);
  SlidingWindow window{SlidingWindowConfig{}};
  const PreintegratedImu pre = Preintegrate(imu, 0, InitialGuess());
  EXPECT_FALSE(window.AddState(0.1, pre).ok);  // not initialised
  EXPECT_FALSE(window.Optimize().converged);
  ASSERT_TRUE(window.Initialize(0.0, InitialGuess()).ok);
  EXPECT_FALSE(window.Initialize(0.0, InitialGuess()).ok);
  const Status late = window.AddState(0.15, pre);  // the preintegration spans 0.1 s
  EXPECT_FALSE(late.ok);
  EXPECT_NE(late.message.find("max_dt_mismatch_s"), std::string::npos) << late.message;
  EXPECT_FALSE(window.AddState(0.0, pre).ok);
  LidarPoseMeasurement bad;
  bad.information(2, 2) = std::nan("");
  EXPECT_FALSE(window.AddState(0.1, pre, bad).ok);
  EXPECT_EQ(window.size(), 1);
  ASSERT_TRUE(window.AddState(0.1, pre).ok);
  const NavState predicted = window.PredictFromLatest(Preintegrate(imu, 1, InitialGuess()));
  const NavState expected = Preintegrate(imu, 1, InitialGuess()).Predict(window.latest_state(), kGravity);
  EXPECT_LT((predicted.p_world_m - expected.p_world_m).norm(), 1e-15);
  EXPECT_EQ(window.latest_time_s(), 0.1);
}

TEST(SlidingWindowConfig, ValidateNamesTheField) {
  std::string error;
  EXPECT_TRUE(SlidingWindowConfig{}.Validate(&error)) << error;
  SlidingWindowConfig c;
  c.window_size = 1;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("sliding_window.window_size"), std::string::npos) << error;
  c = SlidingWindowConfig{};
  c.initial_accel_bias_sigma_mps2 = 0.0;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("initial_accel_bias_sigma_mps2"), std::string::npos) << error;
  c = SlidingWindowConfig{};
  c.gravity_random_walk_rad_per_sqrt_s = 0.0;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("gravity_random_walk_rad_per_sqrt_s"), std::string::npos) << error;
  c = SlidingWindowConfig{};
  c.gravity_world_mps2.setZero();
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("gravity_world_mps2"), std::string::npos) << error;
  c = SlidingWindowConfig{};
  c.lidar_loss_scale = -1.0;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("lidar_loss_scale"), std::string::npos) << error;
}

}  // namespace
}  // namespace rotolidar
