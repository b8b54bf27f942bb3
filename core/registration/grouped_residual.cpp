#include "core/registration/grouped_residual.hpp"

#include <algorithm>
#include <cmath>

#include <ceres/manifold.h>
#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>

#include "core/util/log.hpp"

namespace rotolidar {
namespace {

/// Pivots at or below this fraction of the largest are directions the group does not observe (zero rows).
constexpr double kRelativePivotFloor = 1e-14;

/// G (lower triangle) += w J^T J and g += w J^T r for one point's rows (J: Rows x 6, row-major). Plain loops:
/// Eigen's rank update of a fixed-size matrix goes through its general product kernels (measured 3x slower).
template <int Rows>
void AccumulateWeighted(const double* J, const double* r, double w, Matrix6d* G, Vector6d* g) {
  for (int row = 0; row < Rows; ++row) {
    const double* Jr = J + 6 * row;
    double wj[6];
    for (int a = 0; a < 6; ++a) wj[a] = w * Jr[a];
    for (int a = 0; a < 6; ++a) {
      (*g)(a) += wj[a] * r[row];
      for (int b = 0; b <= a; ++b) (*G)(a, b) += wj[a] * Jr[b];
    }
  }
}

/// The group's model (c, g, G in the tangent delta = [dt; dtheta], residuals.hpp) as the cost function's rows:
/// J rows 0..5 (row-major, 7 ambient columns), residuals r[0..5], the cost row r[6] with a zero Jacobian row.
/// Ceres chains the ambient rows with the manifold's PlusJacobian P (7 x 6) in ITS tangent [dt; dtheta / 2]
/// (residuals.hpp), where the model is G_c = C G C, g_c = C g with C = diag(I, 2 I). So with the pivoted
/// G_c = P_^T L D L^T P_ (LDLT), the tangent rows are R_c = D^(1/2) L^T P_ and z = D^(-1/2) L^-1 P_ g_c, and the
/// ambient rows R_c P^+ (P^+ = (P^T P)^-1 P^T, so R_c P^+ P = R_c).
void WriteSquareRootRows(const Matrix6d& G, const Vector6d& g, double c, const double* x, double* r, double* J) {
  const Eigen::DiagonalMatrix<double, 6> C((Vector6d() << 1, 1, 1, 2, 2, 2).finished());
  const Matrix6d G_c = C * G * C;
  const Eigen::LDLT<Matrix6d> ldlt(G_c);
  Matrix6d perm = Matrix6d::Identity();
  perm = ldlt.transpositionsP() * perm;
  const Matrix6d LtP = Matrix6d(ldlt.matrixU()) * perm;
  Vector6d y = ldlt.transpositionsP() * (C * g);
  ldlt.matrixL().solveInPlace(y);  // L^-1 P_ g_c
  // The quaternion block of P (the translation block is the identity) and its pseudo-inverse.
  Eigen::Matrix<double, 4, 3, Eigen::RowMajor> Q;
  ceres::EigenQuaternionManifold().PlusJacobian(x + 3, Q.data());
  const Eigen::Matrix<double, 3, 4> Q_pinv = (Q.transpose() * Q).inverse() * Q.transpose();
  const Vector6d& D = ldlt.vectorD();
  const double floor = kRelativePivotFloor * std::max(0.0, D.maxCoeff());
  Eigen::Map<Eigen::Matrix<double, 7, 7, Eigen::RowMajor>> rows(J);
  double z_sq = 0.0;
  for (int k = 0; k < 6; ++k) {
    if (!(D(k) > floor && D(k) > 0.0)) {
      r[k] = 0.0;
      rows.row(k).setZero();
      continue;
    }
    const double sqrt_d = std::sqrt(D(k));
    r[k] = y(k) / sqrt_d;
    z_sq += r[k] * r[k];
    rows.row(k).head<3>() = sqrt_d * LtP.row(k).head<3>();
    rows.row(k).tail<4>() = sqrt_d * LtP.row(k).tail<3>() * Q_pinv;
  }
  r[6] = std::sqrt(std::max(0.0, c - z_sq));
  rows.row(6).setZero();
}

}  // namespace

template <typename Residual>
GroupedResidual<Residual>::GroupedResidual(const ceres::LossFunction* loss) : loss_(loss) {
  mutable_parameter_block_sizes()->push_back(7);
  set_num_residuals(kRows);
}

template <typename Residual>
bool GroupedResidual<Residual>::Evaluate(double const* const* parameters, double* residuals,
                                         double** jacobians) const {
  constexpr int kPointRows = Residual::kRows;
  const double* x = parameters[0];
  const Eigen::Vector3d t(x[0], x[1], x[2]);
  const Eigen::Matrix3d R = Eigen::Quaterniond(x[6], x[3], x[4], x[5]).toRotationMatrix();  // unit (manifold)
  double* J = (jacobians != nullptr) ? jacobians[0] : nullptr;
  double c = 0.0;  // sum_i rho(s_i)
  Vector6d g = Vector6d::Zero();
  Matrix6d G = Matrix6d::Zero();
  double r_i[kPointRows], J_i[kPointRows * 6];
  for (const Residual* point : points_) {
    if (J != nullptr)
      point->Linearize(R, t, r_i, J_i);
    else
      point->Residual(R, t, r_i);
    double s = 0.0;
    for (double v : r_i) s += v * v;
    double rho[3] = {s, 1.0, 0.0};
    if (loss_ != nullptr) {
      loss_->Evaluate(s, rho);
      // Ceres' Corrector is a pure sqrt(rho') scaling only here; otherwise it adds a curvature term.
      ROTOLIDAR_CHECK(s == 0.0 || rho[2] <= 0.0, "grouped residuals need a loss with rho'' <= 0, got " << rho[2]);
    }
    c += rho[0];
    if (J != nullptr) AccumulateWeighted<kPointRows>(J_i, r_i, rho[1], &G, &g);
  }
  if (J == nullptr) {
    std::fill(residuals, residuals + kRows - 1, 0.0);
    residuals[kRows - 1] = std::sqrt(c);
    return true;
  }
  G.template triangularView<Eigen::StrictlyUpper>() = G.transpose();
  WriteSquareRootRows(G, g, c, x, residuals, J);
  return true;
}

template class GroupedResidual<PointToPlaneResidual>;
template class GroupedResidual<PointToLineResidual>;

}  // namespace rotolidar
