#pragma once
// IMU model: exact kinematics of a rigidly mounted IMU plus Kalibr's noise model and per-run sensor errors
// (docs/noise_models.md).
//
// True signals (TrueSample), in the imu frame:
//   gyro_true  = R_imu_base * omega_base
//   accel_true = R_imu_world * (a_imu_world - g_world),
//   a_imu_world = a_base + R_world_base (alpha x r + omega x (omega x r)),  r = lever arm (T_base_imu)
// A physics engine (MuJoCo) gives the true signals at the IMU site directly; SampleFromTruth takes those.
//
// Measured signals (SampleFromTruth; Sample = SampleFromTruth(TrueSample)):
//   gyro  = M_g * gyro_true  + b_g + sigma_g  * sqrt(rate_hz) * N(0, I)
//   accel = M_a * accel_true + b_a + sigma_a  * sqrt(rate_hz) * N(0, I)
//   b[k]  = b[k-1] + sigma_b * sqrt(t_k - t_(k-1)) * N(0, I)           (random walk, actual step)
//   b[0]  = turn-on bias ~ N(0, sigma_turn_on^2 I)
//   M     = (I + diag(s)) * (I + A),  s_i ~ N(0, scale_sigma^2), A off-diagonal ~ N(0, misalignment_sigma^2)
//   stamp = t + imu_clock_offset_s + imu_clock_drift_ppm * 1e-6 * t   (SensorClock, sim/sensors/sensor_clock.hpp)
// White noise uses the nominal step dt = 1 / rate_hz (Kalibr's discretisation), the walk the actual step.
// Random streams (RandomStream(run_seed, name)): "imu.gyro", "imu.accel" (white), "imu.gyro_bias",
// "imu.accel_bias" (random walks), "imu.turn_on" (turn-on biases), "imu.gyro_scale", "imu.accel_scale",
// "imu.gyro_misalignment", "imu.accel_misalignment" (drawn once at construction, even when the sigma is 0).
#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "core/types/calib.hpp"
#include "core/types/messages.hpp"
#include "core/util/log.hpp"
#include "core/util/rng.hpp"
#include "sim/rig/base_motion.hpp"

namespace YAML {
class Node;
class Emitter;
}  // namespace YAML

namespace rotolidar::sim {

/// Kalibr noise parameters of a consumer MEMS IMU like the Intel RealSense D435i's Bosch BMI055 at 200 Hz:
/// white-noise densities from the BMI055 datasheet, bias random walks from a 3-hour Allan-variance log of a
/// D435i (sources and conversions in docs/noise_models.md).
ImuNoise Bmi055Noise();

/// Per-run sensor errors that are not noise: turn-on biases, scale factors, misalignment, clock offset.
/// Defaults: moderate turn-on biases of a factory-calibrated consumer MEMS IMU; no scale, misalignment or
/// clock error (those are opt-in for fault studies).
struct ImuErrorConfig {
  double gyro_turn_on_sigma_radps = 0.003;  ///< per axis, ~0.17 deg/s
  double accel_turn_on_sigma_mps2 = 0.03;   ///< per axis, ~3 mg
  double gyro_scale_sigma = 0.0;            ///< per-axis scale-factor error sigma [fraction, 0.01 = 1 %]
  double accel_scale_sigma = 0.0;           ///< per-axis scale-factor error sigma [fraction]
  double gyro_misalignment_sigma_rad = 0.0;   ///< sigma of each off-diagonal axis-coupling term [rad]
  double accel_misalignment_sigma_rad = 0.0;  ///< sigma of each off-diagonal axis-coupling term [rad]
  /// Reported stamp = true rig time + imu_clock_offset_s [s]. Note the sign: calib's lidar_clock_offset_s
  /// maps sensor time to rig time; this one maps rig time to the (wrong) IMU stamp.
  double imu_clock_offset_s = 0.0;
  /// The IMU clock's rate error: stamp = t + imu_clock_offset_s + imu_clock_drift_ppm * 1e-6 * t [ppm].
  double imu_clock_drift_ppm = 0.0;

  /// False with a message naming the field when a value is non-finite, a sigma is negative, a scale or
  /// misalignment sigma exceeds 0.2, |imu_clock_offset_s| exceeds 1 s or |imu_clock_drift_ppm| 1000 ppm.
  bool Validate(std::string* error) const;
};

/// Everything the sim needs to model one IMU: its noise (the TRUE values; calib.yaml carries RigCalib::imu)
/// and its per-run errors.
struct ImuConfig {
  ImuNoise noise = Bmi055Noise();
  ImuErrorConfig errors;
  bool Validate(std::string* error) const;  ///< ValidateImuNoise + errors.Validate
};

/// The true state of the IMU's biases at one time (ground truth for bench/).
struct ImuBiasState {
  Eigen::Vector3d gyro_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();
};

/// Stateful (bias walk, random streams): call Sample()/SampleFromTruth() with non-decreasing true times (both
/// share one state; a time going back is a programmer error, ROTOLIDAR_CHECK). Not thread-safe.
class ImuModel {
 public:
  /// `noise` must pass ValidateImuNoise and `errors` Validate (ROTOLIDAR_CHECK).
  ImuModel(const ImuNoise& noise, const Pose3& T_base_imu, uint64_t run_seed, const ImuErrorConfig& errors = {});
  ImuModel(const ImuConfig& config, const Pose3& T_base_imu, uint64_t run_seed)
      : ImuModel(config.noise, T_base_imu, run_seed, config.errors) {}

  /// The measurement for the base kinematics `k` at true time t: SampleFromTruth(TrueSample(k, t)).
  ImuSample Sample(const BaseKinematics& k, Seconds t);
  /// Turns true signals at the IMU (imu frame: angular rate [rad/s], specific force [m/s^2]) at true time t
  /// into a measurement: advances the bias walk to t, applies scale/misalignment, biases and white noise, and
  /// stamps it on the IMU clock (t + imu_clock_offset_s + imu_clock_drift_ppm * 1e-6 * t).
  ImuSample SampleFromTruth(const Eigen::Vector3d& gyro_true_radps, const Eigen::Vector3d& accel_true_mps2,
                            Seconds t);
  /// The noise- and error-free signals (specific force and rate in the imu frame), stamped t. Pure.
  ImuSample TrueSample(const BaseKinematics& k, Seconds t) const;
  /// The biases in effect for the latest sample (turn-on + walk); before any sample, the turn-on biases.
  const ImuBiasState& Bias() const { return bias_; }
  /// The scale/misalignment matrices M_g, M_a drawn at construction (identity when their sigmas are 0).
  const Eigen::Matrix3d& GyroErrorMatrix() const { return M_gyro_; }
  const Eigen::Matrix3d& AccelErrorMatrix() const { return M_accel_; }
  const ImuNoise& noise() const { return noise_; }
  const ImuErrorConfig& errors() const { return errors_; }
  const Pose3& T_base_imu() const { return T_base_imu_; }

 private:
  ImuNoise noise_;
  ImuErrorConfig errors_;
  Pose3 T_base_imu_;
  RandomStream gyro_white_, accel_white_, gyro_walk_, accel_walk_;
  ImuBiasState bias_;
  Eigen::Matrix3d M_gyro_ = Eigen::Matrix3d::Identity(), M_accel_ = Eigen::Matrix3d::Identity();
  bool has_last_t_ = false;
  Seconds last_t_ = 0.0;
};

/// True when `noise` is usable by ImuModel; otherwise false with a message naming the field in *error.
bool ValidateImuNoise(const ImuNoise& noise, std::string* error);

/// YAML (sim/sensors/imu_yaml.cpp). Keys (all optional; absent keys keep *config's values):
///   preset: bmi055            (first resets noise to Bmi055Noise(); the only preset)
///   rate_hz, gyro_noise_density, gyro_random_walk, accel_noise_density, accel_random_walk,
///   gyro_turn_on_sigma_radps, accel_turn_on_sigma_mps2, gyro_scale_sigma, accel_scale_sigma,
///   gyro_misalignment_sigma_rad, accel_misalignment_sigma_rad, imu_clock_offset_s
/// Unknown keys, wrong types and invalid values (Validate) give an error naming file:line and the field; *config
/// is untouched then. A missing node changes nothing.
Status ParseImuConfig(const std::string& file, const YAML::Node& node, ImuConfig* config);
/// Emits every key above except preset, as one mapping (a value of the caller's key).
void EmitImuConfig(YAML::Emitter& out, const ImuConfig& config);

}  // namespace rotolidar::sim
