#pragma once
// Rigid-body helpers. Naming rule (docs/frames.md): T_a_b maps points from frame b into frame a,
// p_a = T_a_b * p_b. Compose by matching inner frames: T_a_c = T_a_b * T_b_c.
#include <Eigen/Geometry>

// The helpers are defined in geometry.cpp, not inline: the Eigen rotation templates they use cost ~2 s of compile
// time in every file that includes this header, and it is included nearly everywhere.

namespace rotolidar {

using Pose3 = Eigen::Isometry3d;  ///< a rigid transform T_a_b; translation in metres

/// Rotation by `angle_rad` about the z axis of the frame it is applied in.
Pose3 RotZ(double angle_rad);

/// Build a pose from a translation [m] and a unit quaternion (normalised here).
Pose3 MakePose(const Eigen::Vector3d& t_m, const Eigen::Quaterniond& q);

/// Interpolate between two poses: linear in translation, slerp in rotation; s in [0, 1].
Pose3 Interpolate(const Pose3& T0, const Pose3& T1, double s);

/// SO(3) exponential map of a rotation vector [rad].
Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& w_rad);

/// SO(3) logarithm: the rotation vector [rad] of R.
Eigen::Vector3d LogSO3(const Eigen::Matrix3d& R);

}  // namespace rotolidar
