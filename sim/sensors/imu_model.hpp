#pragma once
// IMU model: exact kinematics of a rigidly mounted IMU plus Kalibr's noise model (docs/noise_models.md).
//
//   gyro  = R_imu_base * omega_base + b_g + n_g
//   accel = R_imu_world * (a_imu_world - g_world) + b_a + n_a,
//   a_imu_world = a_base + alpha x r + omega x (omega x r),  r = lever arm base origin -> IMU (T_base_imu)
// White noise per sample: density / sqrt(dt_nominal), dt_nominal = 1 / ImuNoise::rate_hz.
// Bias random walk: b += walk * sqrt(dt) * N(0, 1), dt = time since the previous Sample().
// Turn-on bias: N(0, sigma^2) per axis, drawn once at construction.
// Random streams (RandomStream(run_seed, name)): "imu.gyro", "imu.accel" (white), "imu.gyro_bias",
// "imu.accel_bias" (random walks), "imu.turn_on" (turn-on biases).
#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "core/types/calib.hpp"
#include "core/types/messages.hpp"
#include "core/util/rng.hpp"
#include "sim/rig/base_motion.hpp"

namespace rotolidar::sim {

/// Turn-on (constant, per-run) bias sigmas, per axis. Defaults are typical consumer MEMS values.
struct ImuBiasConfig {
  double gyro_turn_on_sigma_radps = 0.003;  ///< ~0.17 deg/s
  double accel_turn_on_sigma_mps2 = 0.03;   ///< ~3 mg
  bool Validate(std::string* error) const;  ///< finite and >= 0
};

/// The true state of the IMU's biases at one time (ground truth for bench/).
struct ImuBiasState {
  Eigen::Vector3d gyro_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();
};

/// Stateful (bias walk, random streams): call Sample() with non-decreasing times. Not thread-safe.
class ImuModel {
 public:
  /// `noise` must have rate_hz > 0 and non-negative finite densities, `bias` must Validate (ROTOLIDAR_CHECK).
  ImuModel(const ImuNoise& noise, const Pose3& T_base_imu, uint64_t run_seed, const ImuBiasConfig& bias = {});

  /// Advances the bias random walk to `t` (t must be >= the previous call's t), then returns the measurement
  /// stamped `t` for the base kinematics `k` at that time.
  ImuSample Sample(const BaseKinematics& k, Seconds t);
  /// The noise- and bias-free measurement (specific force and rate in the imu frame). Pure.
  ImuSample TrueSample(const BaseKinematics& k, Seconds t) const;
  /// The biases in effect for the latest Sample() (turn-on + walk); before any Sample, the turn-on biases.
  const ImuBiasState& Bias() const { return bias_; }
  const ImuNoise& noise() const { return noise_; }
  const Pose3& T_base_imu() const { return T_base_imu_; }

 private:
  ImuNoise noise_;
  Pose3 T_base_imu_;
  RandomStream gyro_white_, accel_white_, gyro_walk_, accel_walk_;
  ImuBiasState bias_;
  bool has_last_t_ = false;
  Seconds last_t_ = 0.0;
};

/// True when `noise` is usable by ImuModel; otherwise false with a message naming the field in *error.
bool ValidateImuNoise(const ImuNoise& noise, std::string* error);

}  // namespace rotolidar::sim
