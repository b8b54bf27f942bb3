#include "core/types/geometry.hpp"

namespace rotolidar {

Pose3 RotZ(double angle_rad) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

Pose3 MakePose(const Eigen::Vector3d& t_m, const Eigen::Quaterniond& q) {
  Pose3 T = Pose3::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = t_m;
  return T;
}

Pose3 Interpolate(const Pose3& T0, const Pose3& T1, double s) {
  const Eigen::Quaterniond q0(T0.linear()), q1(T1.linear());
  return MakePose((1.0 - s) * T0.translation() + s * T1.translation(), q0.slerp(s, q1));
}

Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& w_rad) {
  const double angle = w_rad.norm();
  if (angle < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w_rad / angle).toRotationMatrix();
}

Eigen::Vector3d LogSO3(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

}  // namespace rotolidar
