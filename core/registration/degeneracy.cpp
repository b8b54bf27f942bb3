#include "core/registration/degeneracy.hpp"

#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "core/util/log.hpp"

namespace rotolidar {

bool DegeneracyConfig::Validate(std::string* error) const {
  if (!(min_eigenvalue >= 0.0) || !std::isfinite(min_eigenvalue)) {
    if (error) *error = "degeneracy.min_eigenvalue must be a finite value >= 0 (got " +
                        std::to_string(min_eigenvalue) + ")";
    return false;
  }
  if (!(weak_eigenvalue >= min_eigenvalue) || !std::isfinite(weak_eigenvalue)) {
    if (error) *error = "degeneracy.weak_eigenvalue must be finite and >= degeneracy.min_eigenvalue (got " +
                        std::to_string(weak_eigenvalue) + ")";
    return false;
  }
  if (!(weak_gate_m > 0.0)) {
    if (error) *error = "degeneracy.weak_gate_m must be > 0 (got " + std::to_string(weak_gate_m) + ")";
    return false;
  }
  return true;
}

Matrix6d DisplacementMetric(const std::vector<Eigen::Vector3d>& lever_arms_m) {
  if (lever_arms_m.empty()) return Matrix6d::Identity();
  // Sum of A^T A with A = [I, -[r]x]: [[I, -[r]x], [[r]x, |r|^2 I - r r^T]] (since -[r]x^T = [r]x).
  Eigen::Vector3d sum_r = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sum_rr = Eigen::Matrix3d::Zero();
  for (const auto& r : lever_arms_m) {
    sum_r += r;
    sum_rr += r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose();
  }
  const double n = double(lever_arms_m.size());
  const Eigen::Vector3d m = sum_r / n;
  Eigen::Matrix3d skew_m;
  skew_m << 0.0, -m.z(), m.y(), m.z(), 0.0, -m.x(), -m.y(), m.x(), 0.0;
  Matrix6d G;
  G << Eigen::Matrix3d::Identity(), -skew_m, skew_m, sum_rr / n;
  return G;
}

DegeneracyInfo AnalyzeDegeneracy(const Matrix6d& hessian, const Matrix6d& displacement_metric,
                                 int num_correspondences, const DegeneracyConfig& config) {
  ROTOLIDAR_CHECK(num_correspondences >= 1, "num_correspondences = " << num_correspondences);
  const Matrix6d G = 0.5 * (displacement_metric + displacement_metric.transpose());
  ROTOLIDAR_CHECK(G.llt().info() == Eigen::Success, "displacement metric is not positive definite:\n" << G);
  const Matrix6d A = 0.5 * (hessian + hessian.transpose()) / double(num_correspondences);
  // A v = lambda G v; Eigen returns ascending eigenvalues and G-orthonormal eigenvectors (V^T G V = I).
  const Eigen::GeneralizedSelfAdjointEigenSolver<Matrix6d> eig(A, G, Eigen::ComputeEigenvectors | Eigen::Ax_lBx);
  DegeneracyInfo info;
  info.eigenvalues = eig.eigenvalues();
  info.eigenvectors = eig.eigenvectors();
  info.displacement_metric = G;
  // Zhang et al.: keep the eigen-directions that pass the threshold; the update loses its components along the
  // others. Eigenvalues ascend, so the degenerate ones are the first few.
  int num_degenerate = 0;
  while (num_degenerate < 6 && info.eigenvalues(num_degenerate) < config.min_eigenvalue) ++num_degenerate;
  MarkDegenerate(num_degenerate, &info);
  return info;
}

void MarkDegenerate(int num, DegeneracyInfo* info) {
  ROTOLIDAR_CHECK(num >= 0 && num <= 6, "num = " << num);
  if (num <= int(info->degenerate_directions.size())) return;
  info->degenerate_directions.clear();
  for (int i = 0; i < num; ++i) info->degenerate_directions.push_back(info->eigenvectors.col(i).normalized());
  info->degenerate = num > 0;
  info->projection = ProjectionWithout(*info, num);
}

int GatedDegenerateCount(const DegeneracyInfo& info, const Vector6d& delta_from_guess, const DegeneracyConfig& config) {
  int num = 0;
  for (int i = 0; i < 6 && info.eigenvalues(i) < config.weak_eigenvalue; ++i) {
    // G-orthonormal eigenvectors: delta = sum_i c_i v_i with c_i = v_i^T G delta, the RMS point motion along v_i.
    const double motion_m = std::abs(info.eigenvectors.col(i).dot(info.displacement_metric * delta_from_guess));
    if (info.eigenvalues(i) < config.min_eigenvalue || motion_m > config.weak_gate_m) num = i + 1;
  }
  return num;
}

Matrix6d ProjectionWithout(const DegeneracyInfo& info, int num_smallest) {
  ROTOLIDAR_CHECK(num_smallest >= 0 && num_smallest <= 6, "num_smallest = " << num_smallest);
  if (num_smallest == 0) return Matrix6d::Identity();
  // With G-orthonormal eigenvectors, sum_i v_i v_i^T G = I: the kept part is the sum over the kept directions.
  Matrix6d P = Matrix6d::Zero();
  for (int i = num_smallest; i < 6; ++i)
    P += info.eigenvectors.col(i) * (info.eigenvectors.col(i).transpose() * info.displacement_metric);
  return P;
}

Vector6d RemapUpdate(const DegeneracyInfo& info, const Vector6d& delta) { return info.projection * delta; }

}  // namespace rotolidar
