// LidarRotorFactor (contract and derivation in rotor_offset_factor.hpp).
#include "core/backend/rotor_offset_factor.hpp"

#include "core/backend/pose_jacobians.hpp"
#include "core/imu/preintegration.hpp"

namespace rotolidar {

MotorAxisInImu MotorAxisInImu::From(const Pose3& T_base_motor, const Pose3& T_base_imu) {
  const Pose3 T_imu_motor = T_base_imu.inverse() * T_base_motor;
  MotorAxisInImu m;
  m.axis = T_imu_motor.linear().col(2).normalized();
  m.origin_m = T_imu_motor.translation();
  return m;
}

Pose3 MotorAxisInImu::B(double psi_rad) const {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(-psi_rad, axis).toRotationMatrix();
  T.translation() = origin_m - T.linear() * origin_m;
  return T;
}

LidarRotorFactor::LidarRotorFactor(const LidarPoseMeasurement& measurement, const MotorAxisInImu& motor,
                                   double phi_applied_rad)
    : measurement_(measurement),
      motor_(motor),
      phi_applied_rad_(phi_applied_rad),
      sqrt_information_(SqrtInformation(measurement.information)) {}

Vector6d LidarRotorFactor::Error(const double* pose7, double phi_rad) const {
  detail::PoseView p;
  Pose3 B;
  return Error(pose7, phi_rad, &p, &B);
}

Vector6d LidarRotorFactor::Error(const double* pose7, double phi_rad, detail::PoseView* pose, Pose3* B) const {
  const detail::PoseView& p = *pose = detail::ReadPose(pose7);
  *B = motor_.B(phi_rad - phi_applied_rad_);
  Vector6d e;
  e.head<3>() = p.t + p.R * B->translation() - measurement_.T_world_imu.translation();
  e.tail<3>() = LogSO3(p.R * B->linear() * measurement_.T_world_imu.linear().transpose());
  return e;
}

// With R_p = R Exp(-psi a) and t_p = t + R t_B(psi) (psi = phi - phi_applied):
//   pose (left, world): d e_t = dt - [R t_B]x dtheta,  d e_R = Jl^-1(e_R) dtheta;
//   phi: R_p Exp(-dphi a) = Exp(-dphi R a) R_p (R_B a = a), so d e_R = -Jl^-1(e_R) R a dphi, and
//        d t_B / d psi = [a]x R_B m, so d e_t = R (a x R_B m) dphi.
bool LidarRotorFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  detail::PoseView p;
  Pose3 B;
  const Vector6d e = Error(parameters[0], parameters[1][0], &p, &B);
  Eigen::Map<Vector6d>{residuals} = sqrt_information_ * e;
  if (jacobians == nullptr) return true;
  const Eigen::Matrix3d Jl_inv = detail::LeftJacobianInverse(e.tail<3>());
  const Eigen::Matrix<double, 6, 3> S_t = sqrt_information_.leftCols<3>(), S_r = sqrt_information_.rightCols<3>();
  if (jacobians[0] != nullptr) {
    detail::WriteAmbientPoseJacobian(S_t, -S_t * so3::Hat(p.R * B.translation()) + S_r * Jl_inv, p.q,
                                     jacobians[0]);
  }
  if (jacobians[1] != nullptr) {
    const Eigen::Vector3d de_t = p.R * motor_.axis.cross(B.linear() * motor_.origin_m);
    const Eigen::Vector3d de_R = -Jl_inv * p.R * motor_.axis;
    Eigen::Map<Vector6d>{jacobians[1]} = S_t * de_t + S_r * de_R;
  }
  return true;
}

}  // namespace rotolidar
