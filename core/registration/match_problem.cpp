#include "core/registration/match_problem.hpp"

#include <algorithm>

namespace rotolidar {
namespace {

/// This thread's Ceres context, shared by its problems (a Problem otherwise creates and destroys its own).
ceres::Context* ThreadContext() {
  thread_local const std::unique_ptr<ceres::Context> context(ceres::Context::Create());
  return context.get();
}

/// Makes `pool` (a deque: its elements never move) hold at least n per-point residuals, placeholders from `make`,
/// and spreads its first n over ceil(n / group_size) GroupedResidual blocks in the problem. A group has a fixed
/// number of rows however many points it holds, so the blocks in use stay in the problem and are refilled; only
/// the difference in their number is added or removed.
template <typename Residual, typename MakePlaceholder>
void RegroupBlocks(size_t n, size_t group_size, ceres::Problem* problem, const ceres::LossFunction* loss, double* x,
                   std::deque<Residual>* pool, std::deque<GroupedResidual<Residual>>* groups,
                   std::vector<ceres::ResidualBlockId>* ids, MakePlaceholder make) {
  while (pool->size() < n) make(pool);
  const size_t num_groups = (n + group_size - 1) / group_size;
  for (; ids->size() > num_groups; ids->pop_back()) problem->RemoveResidualBlock(ids->back());
  while (groups->size() < num_groups) groups->emplace_back(loss);
  for (size_t k = 0; k < num_groups; ++k) {
    GroupedResidual<Residual>& g = (*groups)[k];
    g.Clear();
    for (size_t i = k * group_size; i < std::min((k + 1) * group_size, n); ++i) g.Add(&(*pool)[i]);
  }
  while (ids->size() < num_groups)  // the loss is applied per point, inside
    ids->push_back(problem->AddResidualBlock(&(*groups)[ids->size()], nullptr, x));
}

}  // namespace

std::unique_ptr<ceres::LossFunction> MakeLoss(const ScanToMapConfig& c) {
  switch (c.loss) {
    case RobustLoss::kHuber: return std::make_unique<ceres::HuberLoss>(c.loss_scale_m);
    case RobustLoss::kCauchy: return std::make_unique<ceres::CauchyLoss>(c.loss_scale_m);
    case RobustLoss::kNone: break;
  }
  return nullptr;
}

MatchProblem::MatchProblem(const ScanToMapConfig& config) : loss_(MakeLoss(config)) {
  // 6 tangent unknowns: the normal equations (6x6) are far cheaper than a QR of the ~2000 x 6 Jacobian and, with
  // LM's diagonal damping, well conditioned.
  options_.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  options_.max_num_iterations = config.max_solver_iterations;
  options_.num_threads = config.num_threads;
  options_.logging_type = ceres::SILENT;
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.disable_all_safety_checks = true;  // built right here: one 7-double block, fixed-size residuals
  po.enable_fast_removal = true;        // Resize removes blocks: O(1) each instead of a scan of all blocks
  po.context = ThreadContext();
  problem_ = std::make_unique<ceres::Problem>(po);
  problem_->AddParameterBlock(x_.data(), 7, &manifold_);
}

void MatchProblem::Resize(size_t num_lines, size_t num_planes) {
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero(), unit = Eigen::Vector3d::UnitX();
  RegroupBlocks(num_lines, kPointsPerGroup, problem_.get(), loss_.get(), x_.data(), &lines_, &line_groups_,
                &line_ids_, [&](std::deque<PointToLineResidual>* pool) { pool->emplace_back(zero, zero, unit); });
  RegroupBlocks(num_planes, kPointsPerGroup, problem_.get(), loss_.get(), x_.data(), &planes_, &plane_groups_,
                &plane_ids_, [&](std::deque<PointToPlaneResidual>* pool) { pool->emplace_back(zero, unit, 0.0); });
}

ceres::Solver::Summary MatchProblem::Solve(Pose3* T) {
  x_ = PoseToParameters(*T);
  ceres::Solver::Summary summary;
  ceres::Solve(options_, problem_.get(), &summary);
  *T = ParametersToPose(x_.data());
  return summary;
}

}  // namespace rotolidar
