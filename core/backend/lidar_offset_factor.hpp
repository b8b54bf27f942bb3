#pragma once
// The LiDAR factor with the rig's two slowly varying offsets that a registration cannot see by itself.
//
// Rotor-angle offset phi [rad]: the encoder's angle minus the true rotor angle, from an encoder zero error or an
// encoder clock that runs off the LiDAR's (at rotor speed w, a stamp late by dt seconds reads w dt too little: a
// microcontroller's quartz at 20 ppm gains 36 ms in 30 min, 5 deg at 2.6 rad/s). A scan deskewed with angles off
// by phi is the true scan turned by phi about the motor axis, in the base frame: p_meas = A(phi) p_true with
// A(phi) = T_base_motor RotZ(phi) T_base_motor^-1 (docs/frames.md chain). Registration then finds
// T_world_base A^-1, and the imu frame's LiDAR measurement is T_world_imu B(phi) with
//   B(phi) = T_imu_base A(phi)^-1 T_base_imu = T_imu_motor RotZ(-phi) T_imu_motor^-1,
// a turn by -phi about the motor axis a (imu frame) through the motor origin m (imu frame):
//   R_B = Exp(-phi a),  t_B = m - R_B m.
//
// IMU time offset td [s]: IMU stamp = LiDAR (rig) time of the reading + td (a free-running IMU clock: offset plus
// drift). The Estimator shifts every IMU stamp by its estimate td_applied before integrating, so a window state
// at rig time t is the pose at t - tau, tau = td - td_applied; the LiDAR saw the rig at t, tau later:
//   T_world_imu(t) = (R Exp(w tau), t + v tau)   (constant body rate w and world velocity v over tau),
// as VINS-Mono (Qin and Shen, IROS 2018) moves visual features by td.
//
// One scan cannot tell A from a turn of the base, nor a time shift from a pose change; the IMU can: its gravity
// and rotation rates see the base, not the scan, so the window estimates each offset as one block shared by its
// LiDAR factors (core/backend/sliding_window.hpp).
//
// LidarOffsetFactor: r = S [t_p - t_meas; Log(R_p R_meas^T)], T_p = T_world_imu(t) B(phi - phi_applied), with S,
// the measurement and the tangent convention of LidarPoseFactor (core/backend/pose_factors.hpp). phi_applied and
// td_applied are the offsets already removed from this scan's encoder angles and from the IMU stamps (the
// estimates at that time), so the factor sees only what was left. Analytic Jacobians (checked against numeric
// ones in tests/core/backend).
// Thread safety: immutable after construction.
#include <vector>

#include <ceres/ceres.h>

#include "core/backend/pose_factors.hpp"
#include "core/imu/imu_factor.hpp"
#include "core/imu/pose_block_view.hpp"
#include "core/types/geometry.hpp"

namespace rotolidar {

inline constexpr int kRotorOffsetBlockSize = 1;  ///< [phi] in rad
inline constexpr int kImuTimeOffsetBlockSize = 1;   ///< [td] in s

/// T_imu_motor's motor axis and origin in the imu frame, as B(phi) needs them.
struct MotorAxisInImu {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();   ///< unit vector, imu frame
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();  ///< motor origin, imu frame [m]
  static MotorAxisInImu From(const Pose3& T_base_motor, const Pose3& T_base_imu);
  /// B(psi) above [psi in rad].
  Pose3 B(double psi_rad) const;
};

/// Which offsets a LidarOffsetFactor estimates; its parameter blocks, in order:
///   pose (7) | speed-bias (9, with time: v_world moves the pose by v tau) | phi (1, with rotor) | td (1, with time).
struct LidarOffsets {
  bool rotor = false;
  bool time = false;
  bool any() const { return rotor || time; }
};

class LidarOffsetFactor final : public ceres::CostFunction {
 public:
  /// which.any() must hold (else LidarPoseFactor is the factor; a programmer error: ROTOLIDAR_CHECK). The
  /// measurement's rotor_offset_applied_rad, time_offset_applied_s and angular_velocity_imu_radps are used.
  LidarOffsetFactor(const LidarPoseMeasurement& measurement, const MotorAxisInImu& motor, LidarOffsets which);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  /// The unwhitened error [t_p - t_meas; Log(R_p R_meas^T)] at the blocks above (in their order).
  Vector6d Error(double const* const* parameters) const;

 private:
  struct Eval;  ///< the error and the intermediate values its Jacobians need
  Eval Compute(double const* const* parameters) const;

  LidarPoseMeasurement measurement_;
  MotorAxisInImu motor_;
  LidarOffsets which_;
  Matrix6d sqrt_information_;
};

}  // namespace rotolidar
