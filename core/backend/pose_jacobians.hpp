#pragma once
// Jacobian helpers shared by the back end's pose factors (core/backend/pose_factors.hpp states the tangent
// convention: [dt; dtheta], rotation perturbed on the left in the world frame). For the factors' .cpp files.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/imu/imu_factor.hpp"
#include "core/imu/preintegration.hpp"

namespace rotolidar::detail {

/// Jl^-1(phi) = Jr^-1(-phi): Log(Exp(d) Exp(phi)) ~= phi + Jl^-1(phi) d.
inline Eigen::Matrix3d LeftJacobianInverse(const Eigen::Vector3d& phi) { return so3::RightJacobianInverse(-phi); }

/// The EigenQuaternionManifold's PlusJacobian at unit q (x y z w): orthonormal columns, all orthogonal to q.
inline Eigen::Matrix<double, 4, 3> QuaternionPlusJacobian(const Eigen::Quaterniond& q) {
  Eigen::Matrix<double, 4, 3> P;
  P.topRows<3>() = q.w() * Eigen::Matrix3d::Identity() - so3::Hat(q.vec());
  P.bottomRows<1>() = -q.vec().transpose();
  return P;
}

/// Writes [J_t, 2 J_theta P^T] (rows x 7, row-major) from tangent Jacobians J_t (rows x 3) and J_theta (rows x 3):
/// the exact derivative of r(t, q / |q|) (see pose_factors.hpp).
inline void WriteAmbientPoseJacobian(const Eigen::MatrixXd& J_t, const Eigen::MatrixXd& J_theta,
                                     const Eigen::Quaterniond& q, double* out) {
  using RowMajorXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  Eigen::Map<RowMajorXd> J(out, J_t.rows(), kImuPoseBlockSize);
  J.leftCols<3>() = J_t;
  J.rightCols<4>() = 2.0 * J_theta * QuaternionPlusJacobian(q).transpose();
}

}  // namespace rotolidar::detail
