#pragma once
// Rigid-body helpers. Naming rule (docs/frames.md): T_a_b maps points from frame b into frame a,
// p_a = T_a_b * p_b. Compose by matching inner frames: T_a_c = T_a_b * T_b_c.
#include <Eigen/Geometry>

namespace rotolidar {

using Pose3 = Eigen::Isometry3d;  ///< a rigid transform T_a_b; translation in metres

/// Rotation by `angle_rad` about the z axis of the frame it is applied in.
inline Pose3 RotZ(double angle_rad) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

/// Build a pose from a translation [m] and a unit quaternion (normalised here).
inline Pose3 MakePose(const Eigen::Vector3d& t_m, const Eigen::Quaterniond& q) {
  Pose3 T = Pose3::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = t_m;
  return T;
}

/// Interpolate between two poses: linear in translation, slerp in rotation; s in [0, 1].
inline Pose3 Interpolate(const Pose3& T0, const Pose3& T1, double s) {
  const Eigen::Quaterniond q0(T0.linear()), q1(T1.linear());
  return MakePose((1.0 - s) * T0.translation() + s * T1.translation(), q0.slerp(s, q1));
}

/// SO(3) exponential map of a rotation vector [rad].
inline Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& w_rad) {
  const double angle = w_rad.norm();
  if (angle < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w_rad / angle).toRotationMatrix();
}

/// SO(3) logarithm: the rotation vector [rad] of R.
inline Eigen::Vector3d LogSO3(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

}  // namespace rotolidar
