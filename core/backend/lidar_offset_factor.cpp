// LidarOffsetFactor (contract and model in lidar_offset_factor.hpp).
#include "core/backend/lidar_offset_factor.hpp"

#include "core/backend/pose_jacobians.hpp"
#include "core/imu/preintegration.hpp"
#include "core/util/log.hpp"

namespace rotolidar {
namespace {

/// Where each optional block sits in the factor's parameter list (-1: absent); the order of LidarOffsets.
struct BlockIndex {
  int v = -1, phi = -1, td = -1;
  explicit BlockIndex(const LidarOffsets& which) {
    int next = 1;  // after the pose
    if (which.time) v = next++;
    if (which.rotor) phi = next++;
    if (which.time) td = next++;
  }
};

}  // namespace

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

LidarOffsetFactor::LidarOffsetFactor(const LidarPoseMeasurement& measurement, const MotorAxisInImu& motor,
                                     LidarOffsets which)
    : measurement_(measurement),
      motor_(motor),
      which_(which),
      sqrt_information_(SqrtInformation(measurement.information)) {
  ROTOLIDAR_CHECK(which.any(), "LidarOffsetFactor without an offset: use LidarPoseFactor");
  set_num_residuals(6);
  std::vector<int32_t>& sizes = *mutable_parameter_block_sizes();
  sizes.push_back(kImuPoseBlockSize);
  if (which.time) sizes.push_back(kImuSpeedBiasBlockSize);
  if (which.rotor) sizes.push_back(kRotorOffsetBlockSize);
  if (which.time) sizes.push_back(kImuTimeOffsetBlockSize);
}

struct LidarOffsetFactor::Eval {
  Vector6d e;
  detail::PoseView p;
  Eigen::Vector3d v = Eigen::Vector3d::Zero();  ///< world velocity (time offset only)
  double tau_s = 0.0;                           ///< td - td_applied
  Eigen::Matrix3d R_tau;                        ///< R Exp(w tau)
  Pose3 B;                                      ///< B(phi - phi_applied)
};

LidarOffsetFactor::Eval LidarOffsetFactor::Compute(double const* const* parameters) const {
  Eval x;
  const BlockIndex at(which_);
  x.p = detail::ReadPose(parameters[0]);
  if (at.v >= 0) x.v = Eigen::Map<const Eigen::Vector3d>(parameters[at.v]);
  const double phi = at.phi >= 0 ? parameters[at.phi][0] : measurement_.rotor_offset_applied_rad;
  if (at.td >= 0) x.tau_s = parameters[at.td][0] - measurement_.time_offset_applied_s;
  x.R_tau = x.p.R * ExpSO3(measurement_.angular_velocity_imu_radps * x.tau_s);
  x.B = motor_.B(phi - measurement_.rotor_offset_applied_rad);
  x.e.head<3>() = x.p.t + x.v * x.tau_s + x.R_tau * x.B.translation() - measurement_.T_world_imu.translation();
  x.e.tail<3>() = LogSO3(x.R_tau * x.B.linear() * measurement_.T_world_imu.linear().transpose());
  return x;
}

Vector6d LidarOffsetFactor::Error(double const* const* parameters) const { return Compute(parameters).e; }

// With R_p = R_tau R_B, t_p = t + v tau + R_tau t_B, R_tau = R Exp(w tau), psi = phi - phi_applied:
//   pose (left, world): d e_t = dt - [R_tau t_B]x dtheta,  d e_R = Jl^-1(e_R) dtheta;
//   v: d e_t = tau dv (the biases do not enter);
//   phi: R_p Exp(-dphi a) = Exp(-dphi R_tau a) R_p (R_B a = a), so d e_R = -Jl^-1(e_R) R_tau a dphi, and
//        d t_B / d psi = [a]x R_B m, so d e_t = R_tau (a x R_B m) dphi;
//   td: R_tau Exp(w dtau) = Exp(R w dtau) R_tau (R_tau w = R w), so d e_R = Jl^-1(e_R) R w dtau, and
//       d e_t = (v + R_tau (w x t_B)) dtau.
bool LidarOffsetFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Eval x = Compute(parameters);
  Eigen::Map<Vector6d>{residuals} = sqrt_information_ * x.e;
  if (jacobians == nullptr) return true;
  const Eigen::Matrix3d Jl_inv = detail::LeftJacobianInverse(x.e.tail<3>());
  const Eigen::Matrix<double, 6, 3> S_t = sqrt_information_.leftCols<3>(), S_r = sqrt_information_.rightCols<3>();
  const Eigen::Vector3d& w = measurement_.angular_velocity_imu_radps;
  if (jacobians[0] != nullptr) {
    detail::WriteAmbientPoseJacobian(S_t, -S_t * so3::Hat(x.R_tau * x.B.translation()) + S_r * Jl_inv, x.p.q,
                                     jacobians[0]);
  }
  const BlockIndex at(which_);
  if (at.v >= 0 && jacobians[at.v] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 6, kImuSpeedBiasBlockSize, Eigen::RowMajor>> J(jacobians[at.v]);
    J.setZero();
    J.leftCols<3>() = x.tau_s * S_t;
  }
  if (at.phi >= 0 && jacobians[at.phi] != nullptr) {
    const Eigen::Vector3d de_t = x.R_tau * motor_.axis.cross(x.B.linear() * motor_.origin_m);
    const Eigen::Vector3d de_R = -Jl_inv * x.R_tau * motor_.axis;
    Eigen::Map<Vector6d>{jacobians[at.phi]} = S_t * de_t + S_r * de_R;
  }
  if (at.td >= 0 && jacobians[at.td] != nullptr) {
    const Eigen::Vector3d de_t = x.v + x.R_tau * w.cross(x.B.translation());
    const Eigen::Vector3d de_R = Jl_inv * x.p.R * w;
    Eigen::Map<Vector6d>{jacobians[at.td]} = S_t * de_t + S_r * de_R;
  }
  return true;
}

}  // namespace rotolidar
