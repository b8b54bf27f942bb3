#pragma once
// A run of per-point registration residuals (PointToPlaneResidual or PointToLineResidual, residuals.hpp) as ONE
// Ceres cost function on the 7-double pose block, every point under its own robust loss, compressed to a fixed
// 7 rows whatever the number of points.
//
// What Ceres gets: for the group's points i with residual r_i, tangent Jacobian J_i (kRows x 6, w.r.t.
// delta = [dt; dtheta], Linearize), s_i = |r_i|^2 and loss rho (nullptr: rho(s) = s), Ceres' Corrector for a
// per-point block with that loss (the rho'' <= 0 branch; Huber and Cauchy never take the other) makes the
// block's contribution cost 1/2 rho(s_i), gradient rho'(s_i) J_i^T r_i and Gauss-Newton matrix
// rho'(s_i) J_i^T J_i. Summed over the group: c = sum rho(s_i), g = sum rho' J_i^T r_i, G = sum rho' J_i^T J_i
// (6x6, PSD). The rows are the square-root information form of that model at the evaluation point: 6 rows R, z
// with R^T R = G and R^T z = g (pivoted LDLT; expressed in Ceres' own quaternion tangent and lifted to the 7
// ambient columns through the manifold's PlusJacobian, grouped_residual.cpp), and one cost row
// sqrt(max(0, c - |z|^2)) with a zero Jacobian, so that 1/2 |rows|^2 = c / 2. Gradient, Gauss-Newton matrix
// (hence Jacobi scaling and every LM step), model cost change and cost equal those of one block per point up to
// float rounding (scan_to_map_test pins the LM path); pivots <= 1e-14 max (directions the group does not
// observe) give zero rows. Evaluations without Jacobians (Ceres' candidate costs) return zeros and sqrt(c).
// Why: Ceres' per-row work (dense Jacobian writing and validation, the manifold product, J^T J) and the
// per-point ambient quaternion Jacobian scaled with the ~1000-2000 rows of a scan; now 7 rows per group.
//
// Ownership: does not own the points or the loss; both must outlive every Evaluate. Thread-safety: Evaluate is
// const and re-entrant; Clear / Add only between solves.
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include "core/registration/residuals.hpp"

namespace rotolidar {

template <typename Residual>
class GroupedResidual final : public ceres::CostFunction {
 public:
  static constexpr int kRows = 7;  ///< 6 square-root-information rows + 1 cost row

  /// `loss` must have rho'' <= 0 wherever it is evaluated (checked in Evaluate), or be nullptr.
  explicit GroupedResidual(const ceres::LossFunction* loss);
  void Clear() { points_.clear(); }
  void Add(const Residual* point) { points_.push_back(point); }
  size_t size() const { return points_.size(); }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  const ceres::LossFunction* loss_;
  std::vector<const Residual*> points_;
};

extern template class GroupedResidual<PointToPlaneResidual>;
extern template class GroupedResidual<PointToLineResidual>;

}  // namespace rotolidar
