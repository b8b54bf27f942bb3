#include "sim/sensors/imu_model.hpp"

#include <cmath>

#include "core/util/log.hpp"

namespace rotolidar::sim {
namespace {

Eigen::Vector3d NormalVector(RandomStream& stream, double sigma) {
  const double x = stream.Normal(), y = stream.Normal(), z = stream.Normal();
  return sigma * Eigen::Vector3d(x, y, z);
}

}  // namespace

bool ImuBiasConfig::Validate(std::string* error) const {
  if (!std::isfinite(gyro_turn_on_sigma_radps) || gyro_turn_on_sigma_radps < 0 ||
      !std::isfinite(accel_turn_on_sigma_mps2) || accel_turn_on_sigma_mps2 < 0) {
    if (error) *error = "ImuBiasConfig: gyro_turn_on_sigma_radps/accel_turn_on_sigma_mps2 must be finite, >= 0";
    return false;
  }
  return true;
}

bool ValidateImuNoise(const ImuNoise& noise, std::string* error) {
  auto fail = [error](const std::string& m) {
    if (error) *error = "ImuNoise: " + m;
    return false;
  };
  if (!std::isfinite(noise.rate_hz) || noise.rate_hz <= 0) return fail("rate_hz must be finite and > 0");
  const double densities[] = {noise.gyro_noise_density, noise.gyro_random_walk, noise.accel_noise_density,
                              noise.accel_random_walk};
  for (double d : densities)
    if (!std::isfinite(d) || d < 0) return fail("noise densities must be finite and >= 0");
  return true;
}

ImuModel::ImuModel(const ImuNoise& noise, const Pose3& T_base_imu, uint64_t run_seed, const ImuBiasConfig& bias)
    : noise_(noise),
      T_base_imu_(T_base_imu),
      gyro_white_(run_seed, "imu.gyro"),
      accel_white_(run_seed, "imu.accel"),
      gyro_walk_(run_seed, "imu.gyro_bias"),
      accel_walk_(run_seed, "imu.accel_bias") {
  std::string error;
  ROTOLIDAR_CHECK(ValidateImuNoise(noise_, &error), error);
  ROTOLIDAR_CHECK(bias.Validate(&error), error);
  RandomStream turn_on(run_seed, "imu.turn_on");
  bias_.gyro_radps = NormalVector(turn_on, bias.gyro_turn_on_sigma_radps);
  bias_.accel_mps2 = NormalVector(turn_on, bias.accel_turn_on_sigma_mps2);
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
  ROTOLIDAR_CHECK(!has_last_t_ || t >= last_t_, "ImuModel::Sample time went back: " << t << " < " << last_t_);
  if (has_last_t_) {
    const double sqrt_dt = std::sqrt(t - last_t_);
    bias_.gyro_radps += NormalVector(gyro_walk_, noise_.gyro_random_walk * sqrt_dt);
    bias_.accel_mps2 += NormalVector(accel_walk_, noise_.accel_random_walk * sqrt_dt);
  }
  has_last_t_ = true;
  last_t_ = t;
  const double sqrt_rate = std::sqrt(noise_.rate_hz);  // 1 / sqrt(dt_nominal)
  ImuSample s = TrueSample(k, t);
  s.gyro_radps += bias_.gyro_radps + NormalVector(gyro_white_, noise_.gyro_noise_density * sqrt_rate);
  s.accel_mps2 += bias_.accel_mps2 + NormalVector(accel_white_, noise_.accel_noise_density * sqrt_rate);
  return s;
}

}  // namespace rotolidar::sim
