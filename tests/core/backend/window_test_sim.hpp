#pragma once
// Synthetic data for the sliding-window tests: an analytic motion, IMU samples from it (constant injected biases,
// with and without Kalibr noise from seeded RandomStreams), LiDAR pose measurements = truth + noise, and a driver
// that runs a window over them. World z up, gravity kGravity; states at 10 Hz, IMU at 200 Hz.
#include <cmath>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include "core/backend/sliding_window.hpp"
#include "core/util/rng.hpp"

namespace rotolidar::window_test {

inline const Eigen::Vector3d kGravity(0.0, 0.0, -9.81);
inline constexpr double kImuRateHz = 200.0;
inline constexpr int kSamplesPerState = 20;        // states at 10 Hz (one VLP-16 revolution)
inline constexpr double kLidarSigmaM = 0.02;       // LiDAR pose noise: 2 cm, 0.3 deg per axis
inline constexpr double kLidarSigmaRad = 0.005;
inline const Eigen::Vector3d kBiasGyro(0.012, -0.018, 0.02);   // injected constant biases
inline const Eigen::Vector3d kBiasAccel(0.08, -0.06, 0.1);

inline Eigen::Matrix3d Rx(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix(); }
inline Eigen::Matrix3d Ry(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix(); }
inline Eigen::Matrix3d Rz(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

/// Smooth motion: R = Rz(yaw) Ry(pitch) Rx(roll), sinusoidal position; rates up to ~0.6 rad/s, |a| ~1 m/s^2.
struct Motion {
  static Eigen::Vector3d Rpy(double t) {
    return {0.3 * std::sin(1.3 * t), 0.25 * std::sin(0.9 * t + 0.4), 0.4 * t + 0.3 * std::sin(0.7 * t)};
  }
  static Eigen::Vector3d RpyDot(double t) {
    return {0.39 * std::cos(1.3 * t), 0.225 * std::cos(0.9 * t + 0.4), 0.4 + 0.21 * std::cos(0.7 * t)};
  }
  static NavState State(double t) {
    const Eigen::Vector3d e = Rpy(t);
    NavState s;
    s.R_world_imu = Rz(e.z()) * Ry(e.y()) * Rx(e.x());
    s.p_world_m = {2.0 * std::sin(0.5 * t) + 0.5 * t, 1.5 * (1.0 - std::cos(0.6 * t)), 0.3 * std::sin(0.8 * t)};
    s.v_world_mps = {std::cos(0.5 * t) + 0.5, 0.9 * std::sin(0.6 * t), 0.24 * std::cos(0.8 * t)};
    s.bias_gyro_radps = kBiasGyro;
    s.bias_accel_mps2 = kBiasAccel;
    return s;
  }
  /// Error-free readings: body rate R^T dR/dt = [w]x and specific force R^T (a - g).
  static void Readings(double t, Eigen::Vector3d* gyro, Eigen::Vector3d* accel) {
    const Eigen::Vector3d e = Rpy(t), d = RpyDot(t);
    const Eigen::Matrix3d RxT = Rx(e.x()).transpose(), RyT = Ry(e.y()).transpose();
    *gyro = RxT * RyT * Eigen::Vector3d(0, 0, d.z()) + RxT * Eigen::Vector3d(0, d.y(), 0) +
            Eigen::Vector3d(d.x(), 0, 0);
    const Eigen::Vector3d a(-0.5 * std::sin(0.5 * t), 0.54 * std::cos(0.6 * t), -0.192 * std::sin(0.8 * t));
    *accel = State(t).R_world_imu.transpose() * (a - kGravity);
  }
};

inline Eigen::Vector3d Noise(RandomStream& rng, double sigma) {
  return {rng.Normal(0.0, sigma), rng.Normal(0.0, sigma), rng.Normal(0.0, sigma)};
}

/// IMU samples at 200 Hz with the injected biases; Kalibr noise when `noisy`: white noise density / sqrt(dt) per
/// sample and a bias random walk of random_walk * sqrt(dt) per sample (ImuNoise defaults).
inline std::vector<ImuSample> MakeImu(double duration_s, bool noisy, uint64_t seed) {
  RandomStream white(seed, "sliding_window_test.imu_white"), walk(seed, "sliding_window_test.imu_walk");
  const ImuNoise n;
  const double dt = 1.0 / kImuRateHz;
  Eigen::Vector3d bg = kBiasGyro, ba = kBiasAccel;
  std::vector<ImuSample> out;
  for (int k = 0; k <= static_cast<int>(std::lround(duration_s * kImuRateHz)); ++k) {
    ImuSample s;
    s.t_s = k * dt;
    Motion::Readings(s.t_s, &s.gyro_radps, &s.accel_mps2);
    s.gyro_radps += bg;
    s.accel_mps2 += ba;
    if (noisy) {
      s.gyro_radps += Noise(white, n.gyro_noise_density / std::sqrt(dt));
      s.accel_mps2 += Noise(white, n.accel_noise_density / std::sqrt(dt));
      bg += Noise(walk, n.gyro_random_walk * std::sqrt(dt));
      ba += Noise(walk, n.accel_random_walk * std::sqrt(dt));
    }
    out.push_back(s);
  }
  return out;
}

/// Truth + noise (noise_scale 1: 2 cm, 0.3 deg per axis; 0: exact) with the nominal information.
inline LidarPoseMeasurement MakeLidar(double t, RandomStream& rng, double noise_scale = 1.0) {
  const NavState truth = Motion::State(t);
  LidarPoseMeasurement m;
  const Eigen::Vector3d p_world_m = truth.p_world_m + Noise(rng, noise_scale * kLidarSigmaM);  // drawn first
  const Eigen::Matrix3d R_noise = ExpSO3(Noise(rng, noise_scale * kLidarSigmaRad));
  m.T_world_imu = MakePose(p_world_m, Eigen::Quaterniond(R_noise * truth.R_world_imu));
  m.information.setZero();
  m.information.diagonal() << Eigen::Vector3d::Constant(1.0 / (kLidarSigmaM * kLidarSigmaM)),
      Eigen::Vector3d::Constant(1.0 / (kLidarSigmaRad * kLidarSigmaRad));
  return m;
}

inline PreintegratedImu Preintegrate(const std::vector<ImuSample>& imu, int state_index, const NavState& lin) {
  PreintegratedImu pre(lin.bias_gyro_radps, lin.bias_accel_mps2, ImuNoise{});
  for (int k = state_index * kSamplesPerState; k < (state_index + 1) * kSamplesPerState; ++k) {
    EXPECT_TRUE(pre.Integrate(imu[k], imu[k + 1]).ok);
  }
  return pre;
}

inline double StateTime(int k) { return k * kSamplesPerState / kImuRateHz; }

/// The initial state: truth pose and velocity, biases unknown (zero).
inline NavState InitialGuess() {
  NavState s = Motion::State(0.0);
  s.bias_gyro_radps.setZero();
  s.bias_accel_mps2.setZero();
  return s;
}

struct WindowRun {
  std::vector<NavState> latest;  ///< the latest state after each Optimize (the real-time output), states 1..
  std::vector<NavState> lidar;   ///< the raw LiDAR poses of the same states (the LiDAR-only estimate)
  std::vector<std::vector<WindowStateEstimate>> windows;  ///< every state of the window after each Optimize
  int repropagated = 0;
  bool all_converged = true;
  double solve_time_s = 0.0;  ///< summed Ceres time (reported, never asserted)
  int iterations = 0;         ///< summed Ceres iterations
};

/// Runs num_states states through the window. lidar_for(k, rng) gives state k's measurement (or none); the
/// preintegration is linearised at the latest bias estimate (as the estimator does) or at zero.
template <typename LidarFn>
inline WindowRun RunWindow(SlidingWindow* window, const std::vector<ImuSample>& imu, int num_states, LidarFn lidar_for,
                    bool linearize_at_zero_bias = false) {
  RandomStream rng(5, "sliding_window_test.lidar");
  WindowRun run;
  EXPECT_TRUE(window->Initialize(0.0, InitialGuess(), lidar_for(0, rng)).ok);
  for (int k = 1; k < num_states; ++k) {
    const NavState lin = linearize_at_zero_bias ? InitialGuess() : window->latest_state();
    const std::optional<LidarPoseMeasurement> m = lidar_for(k, rng);
    const Status st = window->AddState(StateTime(k), Preintegrate(imu, k - 1, lin), m);
    EXPECT_TRUE(st.ok) << st.message;
    const WindowResult r = window->Optimize();
    run.all_converged = run.all_converged && r.converged;
    run.repropagated += r.repropagated_intervals;
    run.solve_time_s += r.solve_time_s;
    run.iterations += r.iterations;
    run.latest.push_back(window->latest_state());
    run.windows.push_back(window->states());
    NavState raw;
    if (m) raw.p_world_m = m->T_world_imu.translation();
    if (m) raw.R_world_imu = m->T_world_imu.linear();
    run.lidar.push_back(raw);
  }
  return run;
}

}  // namespace rotolidar::window_test
