#pragma once
// Rig calibration: geometry, extrinsics, intrinsics and noise parameters. This is what calib.yaml holds
// (docs/recording_format.md); the estimator knows the rig only through it.
//
// Frames (docs/frames.md): base = the carrier platform; motor = a fixed frame on the base whose z axis is the
// motor axis; rotor = the motor frame turned by the rotor angle theta about z; lidar, imu and cam as named.
//   T_base_rotor(theta) = T_base_motor * RotZ(theta)
//   T_base_lidar(theta) = T_base_rotor(theta) * T_rotor_lidar
#include <array>
#include <string>

#include "core/types/geometry.hpp"

namespace rotolidar {

/// VLP-16 range limits (VLP-16 user manual): returns inside the blind zone are dropped; rated range 100 m; real
/// units report returns up to ~130 m. The decoder's filter, the calibration and `rotolidar decode` start from these.
constexpr double kVlp16BlindZoneM = 0.4;
constexpr double kVlp16RatedRangeM = 100.0;
constexpr double kVlp16MaxReportedRangeM = 130.0;

/// VLP-16 laser geometry (manual Table 9-1), indexed by laser ID (firing order).
struct LidarIntrinsics {
  std::array<double, 16> elevation_deg{-15, 1, -13, 3, -11, 5, -9, 7, -7, 9, -5, 11, -3, 13, -1, 15};
  std::array<double, 16> vertical_offset_m{0.0112, -0.0007, 0.0097, -0.0022, 0.0081, -0.0037, 0.0066, -0.0051,
                                           0.0051, -0.0066, 0.0037, -0.0081, 0.0022, -0.0097, 0.0007, -0.0112};
  double min_range_m = kVlp16BlindZoneM;   ///< returns closer than this are dropped by the decoder [m]
  double max_range_m = kVlp16RatedRangeM;  ///< the sensor's rated range [m]
  /// 1-sigma range noise [m]. The estimator's feature noise gate uses it unless its config sets one
  /// (features.range_sigma_m). 0.01 m: a real VLP-16 on matte surfaces (the manual's "+-3 cm typical" is an
  /// accuracy bound, not a sigma); the sim writes its caster's sigma here.
  double range_sigma_m = 0.01;
  /// Head rotation speed as configured [rev/min]: 300..1200 (the VLP-16 sets it in steps of 60; factory default
  /// 600 = 10 Hz). One scan (revolution) lasts 60 / rpm seconds.
  double rpm = 600.0;
};

/// Kalibr's continuous-time IMU noise model (docs/noise_models.md). Defaults: BMI055 (the D435i's IMU) gyro,
/// ICM-20948-class accelerometer (Bosch BMI055 and TDK ICM-20948 datasheets' noise densities).
struct ImuNoise {
  double rate_hz = 200.0;
  double gyro_noise_density = 2.44e-4;   ///< [rad/s/sqrt(Hz)]
  double gyro_random_walk = 2.0e-5;      ///< [rad/s^2/sqrt(Hz)]
  double accel_noise_density = 2.26e-3;  ///< [m/s^2/sqrt(Hz)]
  double accel_random_walk = 3.0e-4;     ///< [m/s^3/sqrt(Hz)]
};

/// Pinhole + radial-tangential camera (D435i RGB-like defaults: 640x480, ~69 x 42 deg).
struct CameraIntrinsics {
  int width_px = 640, height_px = 480;
  double fx_px = 462.0, fy_px = 462.0, cx_px = 320.0, cy_px = 240.0;
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0;
  double rate_hz = 30.0;
};

/// Motor shaft encoder.
struct EncoderCalib {
  uint32_t counts_per_rev = 4096;  ///< 4096 = 12-bit, 16384 = 14-bit
  double zero_offset_rad = 0.0;    ///< theta = 2*pi*(count + 0.5)/counts_per_rev - zero_offset_rad (bin centre)
  double rate_hz = 1000.0;         ///< nominal sample rate (informational; readers use the stamps)
};

struct RigCalib {
  int format_version = 1;
  Pose3 T_base_motor = Pose3::Identity();
  Pose3 T_rotor_lidar = Pose3::Identity();
  Pose3 T_base_imu = Pose3::Identity();
  Pose3 T_base_cam = Pose3::Identity();
  double motor_speed_radps = 0.0;  ///< nominal rotor speed, for the uniform-rotation fallback [rad/s]
  double lidar_clock_offset_s = 0.0;  ///< rig time = VLP-16 time past the hour (unwrapped) + this [s]
  double epoch_unix_s = 0.0;          ///< the rig clock's epoch as a Unix time [s] (informational)
  /// IMU stamp = rig time + this [s]: the Estimator subtracts it from every IMU stamp it is fed (the window's
  /// online estimate, window.estimate_time_offset, is a correction on top; `rotolidar calibrate` writes it).
  double imu_time_offset_s = 0.0;
  LidarIntrinsics lidar;
  ImuNoise imu;
  CameraIntrinsics camera;
  EncoderCalib encoder;

  /// True when every field is usable; otherwise false with a message naming the field in *error.
  bool Validate(std::string* error) const;

  /// Rotor angle [rad] from a raw encoder count: the centre of the count's bin, minus the zero offset.
  double EncoderAngle(uint32_t count) const;
  /// T_base_motor * RotZ(theta_rad): the rotor frame at motor angle theta [rad].
  Pose3 T_base_rotor(double theta_rad) const;
  /// T_base_rotor(theta_rad) * T_rotor_lidar.
  Pose3 T_base_lidar(double theta_rad) const;
};

}  // namespace rotolidar
