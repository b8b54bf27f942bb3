#pragma once
// The Ceres side of scan-to-map registration (core/registration/scan_to_map.hpp): ONE ceres::Problem over the
// 7-double pose block (PoseManifold, residuals.hpp) that every correspondence set of a Register call is solved
// in. The matches live in two pools of per-point cost functions (point-to-line, point-to-plane; re-targeted in
// place with SetLine / SetPlane); the problem holds them as GroupedResidual blocks (grouped_residual.hpp) of up
// to kPointsPerGroup consecutive points each, every point under the configured per-point robust loss applied
// inside the group exactly as Ceres applies a block's loss, each group compressed to 7 rows (its square-root
// information). So the gradient, Gauss-Newton matrix, LM steps, costs and optimum are those of the problem with
// one residual block per match under that loss (up to float rounding; pinned by scan_to_map_test's MatchProblem
// tests), while Ceres' per-block and per-row work (evaluation dispatch, Jacobian writing, manifold products,
// J^T J) shrinks from one block and 1-2 rows per point to one block and 7 rows per group.
//
// Thread-safety: one MatchProblem per thread (it is not re-entrant); distinct instances are independent (the
// Ceres context is per thread).
#include <cstddef>
#include <deque>
#include <memory>
#include <vector>

#include <ceres/ceres.h>
#include <Eigen/Core>

#include "core/registration/grouped_residual.hpp"
#include "core/registration/residuals.hpp"
#include "core/registration/scan_to_map.hpp"
#include "core/types/geometry.hpp"

namespace rotolidar {

/// The configured robust loss for one residual [m]: Huber / Cauchy with scale loss_scale_m, or nullptr (none).
std::unique_ptr<ceres::LossFunction> MakeLoss(const ScanToMapConfig& c);

class MatchProblem {
 public:
  /// Points per residual block: large enough that Ceres' per-block overhead vanishes, small enough that
  /// num_threads > 1 still has blocks to spread.
  static constexpr size_t kPointsPerGroup = 64;

  /// Solver options (DENSE_NORMAL_CHOLESKY, max_solver_iterations, num_threads) and loss from `config`.
  explicit MatchProblem(const ScanToMapConfig& config);
  MatchProblem(const MatchProblem&) = delete;
  MatchProblem& operator=(const MatchProblem&) = delete;

  /// The loss every point's residual is under (nullptr: least squares); lives as long as this object.
  const ceres::LossFunction* loss() const { return loss_.get(); }
  /// The options Solve runs Ceres with.
  const ceres::Solver::Options& options() const { return options_; }

  /// Makes the problem hold exactly num_lines point-to-line and num_planes point-to-plane residuals (in
  /// ceil(n / kPointsPerGroup) GroupedResidual blocks of 7 rows per kind).
  /// Points kept from the previous size keep their old correspondence until SetLine / SetPlane: set every index
  /// before Solve.
  void Resize(size_t num_lines, size_t num_planes);
  /// Re-targets line block i < num_lines (PointToLineResidual's contract: |u_map| = 1).
  void SetLine(size_t i, const Eigen::Vector3d& p_scan, const Eigen::Vector3d& a_map, const Eigen::Vector3d& u_map) {
    lines_[i].Reset(p_scan, a_map, u_map);
  }
  /// Re-targets plane block i < num_planes (PointToPlaneResidual's contract: |n_map| = 1).
  void SetPlane(size_t i, const Eigen::Vector3d& p_scan, const Eigen::Vector3d& n_map, double d_m,
                double weight = 1.0) {
    planes_[i].Reset(p_scan, n_map, d_m, weight);
  }

  /// Runs Ceres Levenberg-Marquardt on the current blocks from *T; *T becomes the solution. Returns the summary.
  ceres::Solver::Summary Solve(Pose3* T);

 private:
  std::unique_ptr<ceres::LossFunction> loss_;
  ceres::Solver::Options options_;
  PoseParameters x_{};
  PoseManifold manifold_;
  std::deque<PointToLineResidual> lines_;  ///< pool: the first num_lines (Resize) are in the problem
  std::deque<PointToPlaneResidual> planes_;
  std::deque<GroupedResidual<PointToLineResidual>> line_groups_;  ///< pool: the first line_ids_.size() in use
  std::deque<GroupedResidual<PointToPlaneResidual>> plane_groups_;
  std::vector<ceres::ResidualBlockId> line_ids_, plane_ids_;
  std::unique_ptr<ceres::Problem> problem_;  ///< declared last: destroyed before what it points to
};

}  // namespace rotolidar
