#include "core/graph/pose_graph_factors.hpp"

// Out of line on purpose: the autodiff instantiation and the eigen-solver cost seconds of compile time in every
// file that includes the header (gcc instantiates the templates an inline function uses even where it is unused).
#include <ceres/autodiff_cost_function.h>
#include <Eigen/Eigenvalues>

namespace rotolidar::graph {

Vector6d RelativePoseError(const Pose3& T_world_from, const Pose3& T_world_to, const Pose3& T_from_to_meas) {
  const Pose3 E = T_from_to_meas.inverse() * (T_world_from.inverse() * T_world_to);
  Vector6d e;
  e.head<3>() = E.translation();
  e.tail<3>() = LogSO3(E.linear());
  return e;
}

ceres::CostFunction* RelativePoseResidual::Create(const Pose3& T_from_to_meas, const Matrix6d& sqrt_information) {
  return new ceres::AutoDiffCostFunction<RelativePoseResidual, 6, 3, 4, 3, 4>(
      new RelativePoseResidual(T_from_to_meas, sqrt_information));
}

Status InformationFromCovariance(const Matrix6d& covariance, const InformationFloor& floor,
                                 Matrix6d* information) {
  std::string error;
  if (!floor.Validate(&error)) return Status::Error("InformationFromCovariance: " + error);
  if (!covariance.allFinite()) return Status::Error("InformationFromCovariance: covariance is not finite");
  Vector6d d_inv;
  d_inv << Eigen::Vector3d::Constant(1.0 / floor.min_sigma_translation_m),
      Eigen::Vector3d::Constant(1.0 / floor.min_sigma_rotation_rad);
  // Dimensionless covariance in units of the floors; clamp its eigenvalues to >= 1 (sigma >= floor) and invert.
  const Matrix6d scaled = d_inv.asDiagonal() * (0.5 * (covariance + covariance.transpose())) * d_inv.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(scaled);
  if (eig.info() != Eigen::Success) return Status::Error("InformationFromCovariance: eigen-decomposition failed");
  const Vector6d inv_values = eig.eigenvalues().cwiseMax(1.0).cwiseInverse();
  const Matrix6d scaled_inv = eig.eigenvectors() * inv_values.asDiagonal() * eig.eigenvectors().transpose();
  const Matrix6d info = d_inv.asDiagonal() * scaled_inv * d_inv.asDiagonal();
  *information = 0.5 * (info + info.transpose());
  return Status::Ok();
}

Matrix6d InformationInToFrame(const Matrix6d& information_from, const Pose3& T_from_to) {
  Matrix6d A = Matrix6d::Zero();
  A.topLeftCorner<3, 3>() = T_from_to.linear();
  A.bottomRightCorner<3, 3>() = T_from_to.linear();
  const Matrix6d info = A.transpose() * information_from * A;
  return 0.5 * (info + info.transpose());
}

}  // namespace rotolidar::graph
