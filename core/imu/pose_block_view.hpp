#pragma once
// One pose block [tx ty tz qx qy qz qw] (core/imu/imu_factor.hpp) read once by a factor's Evaluate: the
// quaternion normalised (every factor reads q / |q|, so its Jacobians are those of the normalised pose) and its
// rotation matrix. For the factors' .cpp files.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rotolidar::detail {

struct PoseView {
  Eigen::Vector3d t;     ///< translation [m]
  Eigen::Quaterniond q;  ///< unit quaternion
  Eigen::Matrix3d R;     ///< q as a rotation matrix
};

inline PoseView ReadPose(const double* pose7) {
  PoseView v;
  v.t = Eigen::Map<const Eigen::Vector3d>(pose7);
  v.q = Eigen::Map<const Eigen::Quaterniond>(pose7 + 3).normalized();
  v.R = v.q.toRotationMatrix();
  return v;
}

}  // namespace rotolidar::detail
