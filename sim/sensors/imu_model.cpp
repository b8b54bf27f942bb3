#include "sim/sensors/imu_model.hpp"

#include <cmath>

#include "core/util/log.hpp"
#include "sim/sensors/sensor_clock.hpp"

namespace rotolidar::sim {
namespace {

Eigen::Vector3d NormalVector(RandomStream& stream, double sigma) {
  const double x = stream.Normal(), y = stream.Normal(), z = stream.Normal();
  return sigma * Eigen::Vector3d(x, y, z);
}

/// M = (I + diag(s)) (I + A): per-axis scale errors s and off-diagonal axis coupling A, each from its stream.
Eigen::Matrix3d DrawErrorMatrix(uint64_t run_seed, const char* scale_stream, double scale_sigma,
                                const char* misalignment_stream, double misalignment_sigma) {
  RandomStream scale(run_seed, scale_stream), misalignment(run_seed, misalignment_stream);
  const Eigen::Vector3d s = NormalVector(scale, scale_sigma);
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (r != c) A(r, c) = misalignment_sigma * misalignment.Normal();
  return (Eigen::Vector3d::Ones() + s).asDiagonal() * (Eigen::Matrix3d::Identity() + A);
}

}  // namespace

ImuNoise Bmi055Noise() {
  ImuNoise n;
  n.rate_hz = 200.0;
  n.gyro_noise_density = 0.014 * M_PI / 180.0;  // datasheet 0.014 deg/s/sqrt(Hz) = 2.44e-4 rad/s/sqrt(Hz)
  n.accel_noise_density = 150e-6 * 9.80665;     // datasheet 150 ug/sqrt(Hz) = 1.47e-3 m/s^2/sqrt(Hz)
  n.gyro_random_walk = 2.66e-6;                 // D435i 3 h Allan log (allan_variance_ros), rad/s^2/sqrt(Hz)
  n.accel_random_walk = 1.17e-4;                // same log, m/s^3/sqrt(Hz)
  return n;
}

bool ImuErrorConfig::Validate(std::string* error) const {
  auto fail = [error](const std::string& m) {
    if (error) *error = "ImuErrorConfig: " + m;
    return false;
  };
  const struct {
    const char* name;
    double value, max;
  } sigmas[] = {{"gyro_turn_on_sigma_radps", gyro_turn_on_sigma_radps, 1.0},
                {"accel_turn_on_sigma_mps2", accel_turn_on_sigma_mps2, 10.0},
                {"gyro_scale_sigma", gyro_scale_sigma, 0.2},
                {"accel_scale_sigma", accel_scale_sigma, 0.2},
                {"gyro_misalignment_sigma_rad", gyro_misalignment_sigma_rad, 0.2},
                {"accel_misalignment_sigma_rad", accel_misalignment_sigma_rad, 0.2}};
  for (const auto& s : sigmas)
    if (!std::isfinite(s.value) || s.value < 0 || s.value > s.max)
      return fail(std::string(s.name) + " must be finite and in [0, " + std::to_string(s.max) + "]");
  if (!std::isfinite(imu_clock_offset_s) || std::abs(imu_clock_offset_s) > 1.0)
    return fail("imu_clock_offset_s must be finite and within +-1 s");
  if (!std::isfinite(imu_clock_drift_ppm) || std::abs(imu_clock_drift_ppm) > 1000.0)
    return fail("imu_clock_drift_ppm must be finite and within +-1000 ppm");
  return true;
}

bool ImuConfig::Validate(std::string* error) const {
  return ValidateImuNoise(noise, error) && errors.Validate(error);
}

bool ValidateImuNoise(const ImuNoise& noise, std::string* error) {
  auto fail = [error](const std::string& m) {
    if (error) *error = "ImuNoise: " + m;
    return false;
  };
  if (!std::isfinite(noise.rate_hz) || noise.rate_hz <= 0) return fail("rate_hz must be finite and > 0");
  const struct {
    const char* name;
    double value;
  } densities[] = {{"gyro_noise_density", noise.gyro_noise_density},
                   {"gyro_random_walk", noise.gyro_random_walk},
                   {"accel_noise_density", noise.accel_noise_density},
                   {"accel_random_walk", noise.accel_random_walk}};
  for (const auto& d : densities)
    if (!std::isfinite(d.value) || d.value < 0) return fail(std::string(d.name) + " must be finite and >= 0");
  return true;
}

ImuModel::ImuModel(const ImuNoise& noise, const Pose3& T_base_imu, uint64_t run_seed, const ImuErrorConfig& errors)
    : noise_(noise),
      errors_(errors),
      T_base_imu_(T_base_imu),
      gyro_white_(run_seed, "imu.gyro"),
      accel_white_(run_seed, "imu.accel"),
      gyro_walk_(run_seed, "imu.gyro_bias"),
      accel_walk_(run_seed, "imu.accel_bias") {
  std::string error;
  ROTOLIDAR_CHECK(ValidateImuNoise(noise_, &error), error);
  ROTOLIDAR_CHECK(errors_.Validate(&error), error);
  RandomStream turn_on(run_seed, "imu.turn_on");
  bias_.gyro_radps = NormalVector(turn_on, errors_.gyro_turn_on_sigma_radps);
  bias_.accel_mps2 = NormalVector(turn_on, errors_.accel_turn_on_sigma_mps2);
  M_gyro_ = DrawErrorMatrix(run_seed, "imu.gyro_scale", errors_.gyro_scale_sigma, "imu.gyro_misalignment",
                            errors_.gyro_misalignment_sigma_rad);
  M_accel_ = DrawErrorMatrix(run_seed, "imu.accel_scale", errors_.accel_scale_sigma, "imu.accel_misalignment",
                             errors_.accel_misalignment_sigma_rad);
}

ImuSample ImuModel::TrueSample(const BaseKinematics& k, Seconds t) const {
  const Eigen::Matrix3d R_world_base = k.T_world_base.linear();
  const Eigen::Matrix3d R_imu_base = T_base_imu_.linear().transpose();
  const Eigen::Vector3d& w = k.omega_base_radps;
  const Eigen::Vector3d r_base = T_base_imu_.translation();
  // Rigid-body acceleration of the IMU site, relative part computed in the base frame.
  const Eigen::Vector3d a_rel_base = k.alpha_base_radps2.cross(r_base) + w.cross(w.cross(r_base));
  const Eigen::Vector3d a_imu_world = k.a_world_mps2 + R_world_base * a_rel_base;
  ImuSample s;
  s.t_s = t;
  s.gyro_radps = R_imu_base * w;
  s.accel_mps2 = R_imu_base * (R_world_base.transpose() * (a_imu_world - GravityWorld()));
  return s;
}

ImuSample ImuModel::Sample(const BaseKinematics& k, Seconds t) {
  const ImuSample truth = TrueSample(k, t);
  return SampleFromTruth(truth.gyro_radps, truth.accel_mps2, t);
}

ImuSample ImuModel::SampleFromTruth(const Eigen::Vector3d& gyro_true_radps, const Eigen::Vector3d& accel_true_mps2,
                                    Seconds t) {
  ROTOLIDAR_CHECK(std::isfinite(t), "ImuModel: time is not finite");
  ROTOLIDAR_CHECK(!has_last_t_ || t >= last_t_, "ImuModel: time went back: " << t << " < " << last_t_);
  if (has_last_t_) {
    const double sqrt_dt = std::sqrt(t - last_t_);
    bias_.gyro_radps += NormalVector(gyro_walk_, noise_.gyro_random_walk * sqrt_dt);
    bias_.accel_mps2 += NormalVector(accel_walk_, noise_.accel_random_walk * sqrt_dt);
  }
  has_last_t_ = true;
  last_t_ = t;
  const double sqrt_rate = std::sqrt(noise_.rate_hz);  // 1 / sqrt(dt_nominal)
  ImuSample s;
  s.t_s = SensorClock{errors_.imu_clock_offset_s, errors_.imu_clock_drift_ppm}.Stamp(t);
  s.gyro_radps = M_gyro_ * gyro_true_radps + bias_.gyro_radps +
                 NormalVector(gyro_white_, noise_.gyro_noise_density * sqrt_rate);
  s.accel_mps2 = M_accel_ * accel_true_mps2 + bias_.accel_mps2 +
                 NormalVector(accel_white_, noise_.accel_noise_density * sqrt_rate);
  return s;
}

}  // namespace rotolidar::sim
