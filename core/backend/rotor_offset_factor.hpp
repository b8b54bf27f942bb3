#pragma once
// The rotor-angle offset seen through the LiDAR factor. phi [rad] is the encoder's angle minus the true rotor
// angle: an encoder zero error, or an encoder clock that runs off the LiDAR's (at rotor speed w, a stamp late by
// dt seconds reads w dt too little: a microcontroller's quartz at 20 ppm gains 36 ms in 30 min, 5 deg at
// 2.6 rad/s). A scan deskewed with angles off by phi is the true scan turned by phi about the motor axis, in the
// base frame: p_meas = A(phi) p_true with A(phi) = T_base_motor RotZ(phi) T_base_motor^-1 (docs/frames.md chain).
// Registration then finds T_world_base A^-1, and the imu frame's LiDAR measurement is T_world_imu B(phi) with
//   B(phi) = T_imu_base A(phi)^-1 T_base_imu = T_imu_motor RotZ(-phi) T_imu_motor^-1,
// a turn by -phi about the motor axis a (imu frame) through the motor origin m (imu frame):
//   R_B = Exp(-phi a),  t_B = m - R_B m.
// One scan cannot tell A from a turn of the base (both move the whole scan rigidly); the IMU can: its gravity and
// its rotation rates see the base, not the scan, so the window estimates phi as one block shared by its LiDAR
// factors (core/backend/sliding_window.hpp).
//
// LidarRotorFactor: r = S [t_p - t_meas; Log(R_p R_meas^T)], T_p = T_world_imu B(phi - phi_applied), with S, the
// measurement and the tangent convention of LidarPoseFactor (core/backend/pose_factors.hpp). phi_applied is the
// offset the deskew already removed from this scan's encoder angles (the estimate at that time), so the factor
// sees only what was left. Analytic Jacobians (checked against numeric ones in tests/core/backend).
// Thread safety: immutable after construction.
#include <ceres/ceres.h>

#include "core/backend/pose_factors.hpp"
#include "core/imu/imu_factor.hpp"
#include "core/imu/pose_block_view.hpp"
#include "core/types/geometry.hpp"

namespace rotolidar {

inline constexpr int kRotorOffsetBlockSize = 1;  ///< [phi] in rad

/// T_imu_motor's motor axis and origin in the imu frame, as B(phi) needs them.
struct MotorAxisInImu {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();   ///< unit vector, imu frame
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();  ///< motor origin, imu frame [m]
  static MotorAxisInImu From(const Pose3& T_base_motor, const Pose3& T_base_imu);
  /// B(psi) above [psi in rad].
  Pose3 B(double psi_rad) const;
};

class LidarRotorFactor final : public ceres::SizedCostFunction<6, kImuPoseBlockSize, kRotorOffsetBlockSize> {
 public:
  LidarRotorFactor(const LidarPoseMeasurement& measurement, const MotorAxisInImu& motor, double phi_applied_rad);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  /// The unwhitened error [t_p - t_meas; Log(R_p R_meas^T)].
  Vector6d Error(const double* pose7, double phi_rad) const;

 private:
  /// The error at a pose and phi, with the pose as read and B(phi - phi_applied) for the Jacobians.
  Vector6d Error(const double* pose7, double phi_rad, detail::PoseView* pose, Pose3* B) const;

  LidarPoseMeasurement measurement_;
  MotorAxisInImu motor_;
  double phi_applied_rad_;
  Matrix6d sqrt_information_;
};

}  // namespace rotolidar
