#include "core/types/calib.hpp"

#include <cmath>

#include "core/util/validation.hpp"

namespace rotolidar {
namespace {

bool IsRotation(const Pose3& T) {
  const Eigen::Matrix3d R = T.linear();
  return (R * R.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-6 && std::abs(R.determinant() - 1.0) < 1e-6;
}

}  // namespace

bool RigCalib::Validate(std::string* error) const {
  if (format_version != 1) return FailValidation(error, "format_version: expected 1, got " + std::to_string(format_version));
  const std::pair<const char*, const Pose3*> poses[] = {
      {"T_base_motor", &T_base_motor}, {"T_rotor_lidar", &T_rotor_lidar},
      {"T_base_imu", &T_base_imu}, {"T_base_cam", &T_base_cam}};
  for (const auto& [name, T] : poses) {
    if (!T->matrix().allFinite() || !IsRotation(*T)) return FailValidation(error, std::string(name) + ": not a rigid transform");
  }
  if (!std::isfinite(motor_speed_radps)) return FailValidation(error, "motor_speed_radps: not finite");
  if (lidar.min_range_m < 0 || lidar.max_range_m <= lidar.min_range_m)
    return FailValidation(error, "lidar: need 0 <= min_range_m < max_range_m");
  if (!(lidar.range_sigma_m >= 0) || !std::isfinite(lidar.range_sigma_m))
    return FailValidation(error, "lidar.range_sigma_m: must be finite and >= 0");
  if (!(lidar.rpm >= 300 && lidar.rpm <= 1200)) return FailValidation(error, "lidar.rpm: must be in [300, 1200]");
  if (imu.rate_hz <= 0) return FailValidation(error, "imu.rate_hz: must be > 0");
  if (imu.gyro_noise_density < 0 || imu.accel_noise_density < 0 || imu.gyro_random_walk < 0 ||
      imu.accel_random_walk < 0)
    return FailValidation(error, "imu: noise densities must be >= 0");
  if (camera.width_px <= 0 || camera.height_px <= 0 || camera.fx_px <= 0 || camera.fy_px <= 0)
    return FailValidation(error, "camera: width, height, fx, fy must be > 0");
  if (encoder.counts_per_rev < 4) return FailValidation(error, "encoder.counts_per_rev: must be >= 4");
  if (!(std::abs(imu_time_offset_s) <= 1.0))
    return FailValidation(error, "imu_time_offset_s: must be finite and within +-1 s");
  return true;
}

double RigCalib::EncoderAngle(uint32_t count) const {
  // The centre of the count's bin: an encoder reports floor(angle / step), so the centre is unbiased.
  return 2.0 * M_PI * (static_cast<double>(count) + 0.5) / static_cast<double>(encoder.counts_per_rev) -
         encoder.zero_offset_rad;
}

Pose3 RigCalib::T_base_rotor(double theta_rad) const { return T_base_motor * RotZ(theta_rad); }

Pose3 RigCalib::T_base_lidar(double theta_rad) const { return T_base_rotor(theta_rad) * T_rotor_lidar; }

}  // namespace rotolidar
