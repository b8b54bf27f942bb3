#pragma once
// IMU initialisation for the sliding window (docs/backend.md, "Initialisation"):
//   - static start: mean accelerometer -> gravity direction -> roll/pitch (yaw = 0), mean gyro -> gyro bias,
//     over a configurable stillness window with a stillness test;
//   - moving start: LiDAR-only poses of the first N scans + IMU preintegration between them -> gyro bias, then
//     velocities and gravity by linear least squares, gravity refined on the sphere |g| = 9.81 (VINS-Mono's
//     visual-inertial alignment, Qin et al., T-RO 2018, Sec. V; with LiDAR the poses are metric: no scale).
// The accelerometer bias is not estimated: at rest it is indistinguishable from a tilt (ba / g rad of roll/pitch
// error), and over a short moving start it is poorly observable; the sliding window estimates it.
// Frames: "odom" is the frame of the LiDAR-only poses (e.g. the base frame at the first scan); "world" is the
// gravity-aligned frame (z up, g = (0, 0, -|g|)) sharing odom's origin, with R_world_odom the smallest rotation
// that levels odom. Pure functions; thread-safe. Failure: success = false with `reason`; never throws on data.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/imu/preintegration.hpp"
#include "core/types/geometry.hpp"
#include "core/types/messages.hpp"

namespace rotolidar {

struct ImuInitConfig {
  double gravity_mps2 = 9.81;  ///< magnitude of gravity [m/s^2]

  // Static start. Stillness is judged on the IMU low-passed by `static_block_s` block means: a rotary rig's
  // stepper shakes the IMU at lines of 20 Hz and more (50 and 200 steps per rotor turn at 2.6 rad/s), which a
  // 0.2 s mean removes, while a walk's or a vehicle's motion (below ~3 Hz) passes. Measured per axis over 1 s of
  // a standing rig (lab, seed 1): accelerometer 0.21 (typical twin) and 0.40 m/s^2 (harsh: a rougher stepper)
  // per sample, 0.01-0.07 m/s^2 as 0.2 s means (the most while the rotor spins up); a walk 1.7 m/s^2, its first
  // steps above 0.15 m/s^2 within 0.25 s of setting off (why: docs/backend.md, 'Initialisation').
  double static_window_s = 1.0;              ///< the first this many seconds of samples are averaged [s]
  int static_min_samples = 20;               ///< fewer samples in the window -> failure
  double static_block_s = 0.2;               ///< block [s] whose means the spreads below are over; 0: samples
  double static_max_gyro_std_radps = 0.02;   ///< max per-axis standard deviation of the gyro's block means
  double static_max_accel_std_mps2 = 0.15;   ///< max per-axis standard deviation of the accelerometer's
  /// ImuIsStill only: max |mean gyro| [rad/s] (the bias plus a slow turn): 3x the norm of a consumer gyro's
  /// zero-rate offset at its datasheet limit on every axis (BMI055: +-1 deg/s, 0.03 rad/s as a norm).
  double still_max_gyro_mean_radps = 0.1;
  double max_gravity_error_mps2 = 0.5;       ///< static: ||mean accel| - g|; moving: ||g_lsq| - g| above -> failure

  // Moving start.
  int moving_min_poses = 5;          ///< LiDAR poses needed (N >= 3 makes the linear system determined)
  int gyro_bias_iterations = 2;      ///< bias solve + re-integration rounds
  int gravity_refine_iterations = 4; ///< tangent-plane refinements of g on the sphere |g| = gravity_mps2

  bool Validate(std::string* error) const;  ///< false with the offending field named in *error
};

struct ImuInitResult {
  bool success = false;
  std::string reason;  ///< why it failed; empty on success
  /// Orientation of the imu frame at the first pose (moving) or during the still window (static, yaw = 0).
  Eigen::Matrix3d R_world_imu = Eigen::Matrix3d::Identity();
  /// Moving start: the levelling rotation of the odometry frame; static start: identity.
  Eigen::Matrix3d R_world_odom = Eigen::Matrix3d::Identity();
  /// One per LiDAR pose (moving), in world [m/s]; static start: one zero velocity.
  std::vector<Eigen::Vector3d> velocities_world_mps;
  Eigen::Vector3d bias_gyro_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d bias_accel_mps2 = Eigen::Vector3d::Zero();  ///< not estimated (see above): zero / the input's
  /// Static: ||mean accel| - g|. Moving: ||g_lsq| - g| of the unconstrained least squares (before refinement).
  double gravity_residual_mps2 = 0.0;
  /// Moving: gravity in the odometry frame after refinement (|g| = gravity_mps2).
  Eigen::Vector3d gravity_odom_mps2 = Eigen::Vector3d::Zero();
  /// Moving: RMS rotation residual |Log(dR(bg)^T R_k^T R_k+1)| after the gyro-bias fit [rad].
  double rotation_residual_rad = 0.0;
  /// World-frame states, one per pose (moving: positions R_world_odom p_odom) or one (static, at the origin).
  std::vector<NavState> states;
  double t_s = 0.0;  ///< static: time of the last sample used [s]; moving: unused (the poses carry the times)
};

/// Static initialisation from the first config.static_window_s seconds of `samples` (time-ordered, imu frame).
ImuInitResult InitializeStatic(const std::vector<ImuSample>& samples, const ImuInitConfig& config);

/// True when the samples with t_s in [t0_s, t1_s] look like a rig at rest by the static-start thresholds: at least
/// static_min_samples of them, per-axis std of the gyro's and accelerometer's static_block_s means below
/// static_max_*_std (a window under two blocks: the samples' std below 4x those), |mean gyro| below
/// still_max_gyro_mean_radps and ||mean accel| - g| below max_gravity_error_mps2. Otherwise false, with the failed
/// test in *why (may be null).
bool ImuIsStill(const std::vector<ImuSample>& samples, Seconds t0_s, Seconds t1_s, const ImuInitConfig& config,
                std::string* why);

/// Moving initialisation. T_odom_imu[k]: LiDAR-only pose of the imu frame at scan k (convert base poses with
/// T_base_imu first); imu_between[k] integrates [t_k, t_k+1] (size N - 1, any linearisation biases).
ImuInitResult InitializeMoving(const std::vector<Pose3>& T_odom_imu, const std::vector<PreintegratedImu>& imu_between,
                               const ImuInitConfig& config);

}  // namespace rotolidar
