#include "core/graph/pose_graph.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <unordered_set>

#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <Eigen/Cholesky>

#include "core/util/log.hpp"
#include "core/util/validation.hpp"

namespace rotolidar::graph {

namespace {

/// Ceres' copy of one node: [t (3) | q (4, x y z w)].
using NodeParams = std::array<double, 7>;

bool IsValidPose(const Pose3& T) {
  if (!T.matrix().allFinite()) return false;
  const Eigen::Matrix3d R = T.linear();
  // 1e-6: far above the round-off of composed rotations (~1e-15 per product), far below a genuine shear/scale.
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6 && R.determinant() > 0.0;
}

/// Why `information` is unusable as an edge information matrix, or "" when it is symmetric positive definite.
/// On success *sqrt_information = L^T with information = L L^T.
std::string CheckInformation(const Matrix6d& information, Matrix6d* sqrt_information) {
  if (!information.allFinite()) return "information matrix is not finite";
  const double scale = information.cwiseAbs().maxCoeff();
  // Symmetric up to round-off relative to the largest entry (an asymmetric input is a caller's bug: LLT would
  // silently read only the lower triangle).
  if ((information - information.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) {
    return "information matrix is not symmetric";
  }
  const Eigen::LLT<Matrix6d> llt(information);
  if (scale == 0.0 || llt.info() != Eigen::Success) return "information matrix is not positive definite";
  *sqrt_information = llt.matrixL().transpose();
  if (!sqrt_information->allFinite() || (sqrt_information->diagonal().array() <= 0.0).any()) {
    return "information matrix is not positive definite";
  }
  return "";
}

NodeParams ToParams(const Pose3& T) {
  const Eigen::Quaterniond q = Eigen::Quaterniond(T.linear()).normalized();
  return {T.translation().x(), T.translation().y(), T.translation().z(), q.x(), q.y(), q.z(), q.w()};
}

Pose3 FromParams(const NodeParams& p) {
  return MakePose(Eigen::Vector3d(p[0], p[1], p[2]), Eigen::Quaterniond(p[6], p[3], p[4], p[5]));
}

ceres::LossFunction* MakeLoopLoss(LoopLossKind kind, double scale) {
  switch (kind) {
    case LoopLossKind::kNone: return nullptr;
    case LoopLossKind::kHuber: return new ceres::HuberLoss(scale);
    case LoopLossKind::kCauchy: return new ceres::CauchyLoss(scale);
    case LoopLossKind::kTukey: return new ceres::TukeyLoss(scale);
  }
  return nullptr;
}

std::string EdgeName(size_t index, const PoseGraphEdge& e) {
  std::ostringstream os;
  os << "edge " << index << " (" << ToString(e.kind) << ", from " << e.from_id << " to " << e.to_id << ")";
  return os.str();
}

}  // namespace

const char* ToString(EdgeKind kind) { return kind == EdgeKind::kLoop ? "loop" : "odometry"; }

const char* ToString(LoopLossKind kind) {
  switch (kind) {
    case LoopLossKind::kNone: return "none";
    case LoopLossKind::kHuber: return "huber";
    case LoopLossKind::kCauchy: return "cauchy";
    case LoopLossKind::kTukey: return "tukey";
  }
  return "?";
}

bool PoseGraphConfig::Validate(std::string* error) const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(loop_loss_scale)) return FailValidation(error, "pose_graph.loop_loss_scale must be > 0");
  if (max_iterations < 1) return FailValidation(error, "pose_graph.max_iterations must be >= 1");
  if (!(function_tolerance > 0.0 && function_tolerance < 1.0)) {
    return FailValidation(error, "pose_graph.function_tolerance must be in (0, 1)");
  }
  if (!positive(loop_rejection_chi2)) return FailValidation(error, "pose_graph.loop_rejection_chi2 must be > 0");
  if (max_resolve_rounds < 1) return FailValidation(error, "pose_graph.max_resolve_rounds must be >= 1");
  if (num_threads < 1) return FailValidation(error, "pose_graph.num_threads must be >= 1");
  return true;
}

// -------------------------------------------------------------------------------------------------- PoseGraph

PoseGraph::PoseGraph(PoseGraphConfig config) : config_(std::move(config)) {}

Status PoseGraph::AddNode(int id, const Pose3& T_world_node, bool fixed) {
  if (index_of_.count(id) != 0) return Status::Error("pose graph: duplicate node id " + std::to_string(id));
  if (!IsValidPose(T_world_node)) {
    return Status::Error("pose graph: node " + std::to_string(id) + ": pose is not finite or not a rotation");
  }
  index_of_.emplace(id, nodes_.size());
  nodes_.push_back({id, T_world_node, fixed});
  any_fixed_ = any_fixed_ || fixed;
  return Status::Ok();
}

Status PoseGraph::AddEdge(const PoseGraphEdge& edge) {
  const std::string name = "pose graph: " + EdgeName(edges_.size(), edge) + ": ";
  if (!HasNode(edge.from_id)) return Status::Error(name + "unknown node id " + std::to_string(edge.from_id));
  if (!HasNode(edge.to_id)) return Status::Error(name + "unknown node id " + std::to_string(edge.to_id));
  if (edge.from_id == edge.to_id) return Status::Error(name + "connects a node to itself");
  if (!IsValidPose(edge.T_from_to)) return Status::Error(name + "T_from_to is not finite or not a rotation");
  Matrix6d sqrt_information;
  const std::string why = CheckInformation(edge.information, &sqrt_information);
  if (!why.empty()) return Status::Error(name + why);
  edges_.push_back(edge);
  sqrt_information_.push_back(sqrt_information);
  return Status::Ok();
}

const Pose3& PoseGraph::Pose(int id) const {
  const auto it = index_of_.find(id);
  ROTOLIDAR_CHECK(it != index_of_.end(), "pose graph has no node " << id);
  return nodes_[it->second].T_world_node;
}

bool PoseGraph::HasNode(int id) const { return index_of_.count(id) != 0; }

bool PoseGraph::IsFixed(int id) const {
  const auto it = index_of_.find(id);
  if (it == index_of_.end()) return false;
  return any_fixed_ ? nodes_[it->second].fixed : it->second == 0;
}

std::vector<int> PoseGraph::NodeIds() const {
  std::vector<int> ids;
  ids.reserve(nodes_.size());
  for (const Node& n : nodes_) ids.push_back(n.id);
  return ids;
}

namespace {

/// One Optimize call's view of the graph in node / edge index space, and Ceres' copy of the node poses.
struct SolveContext {
  const PoseGraphConfig& config;
  const std::vector<PoseGraphEdge>& edges;
  const std::vector<Matrix6d>& sqrt_information;
  std::vector<size_t> from_index, to_index;  // per edge
  std::vector<bool> fixed;                   // per node
  std::vector<NodeParams> params;            // per node
};

/// A Ceres problem over SolveContext::params. The manifold is declared first, so it outlives the problem, which
/// does not own it (one manifold shared by every quaternion block).
struct GraphProblem {
  static ceres::Problem::Options Options() {
    ceres::Problem::Options options;
    options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    return options;
  }
  ceres::EigenQuaternionManifold quaternion_manifold;
  ceres::Problem problem{Options()};
  std::vector<bool> in_problem;  // per node: touched by a residual
};

/// All edges except the `excluded` ones; loop edges get `loop_loss` (scale from the config).
std::unique_ptr<GraphProblem> BuildProblem(SolveContext& ctx, LoopLossKind loop_loss,
                                           const std::unordered_set<size_t>& excluded) {
  auto gp = std::make_unique<GraphProblem>();
  gp->in_problem.assign(ctx.params.size(), false);
  for (size_t k = 0; k < ctx.edges.size(); ++k) {
    if (excluded.count(k) != 0) continue;
    const PoseGraphEdge& edge = ctx.edges[k];
    double* a = ctx.params[ctx.from_index[k]].data();
    double* b = ctx.params[ctx.to_index[k]].data();
    ceres::LossFunction* loss =
        edge.kind == EdgeKind::kLoop ? MakeLoopLoss(loop_loss, ctx.config.loop_loss_scale) : nullptr;
    gp->problem.AddResidualBlock(RelativePoseResidual::Create(edge.T_from_to, ctx.sqrt_information[k]), loss, a,
                                 a + 3, b, b + 3);
    for (const size_t n : {ctx.from_index[k], ctx.to_index[k]}) {
      if (gp->in_problem[n]) continue;
      gp->in_problem[n] = true;
      double* p = ctx.params[n].data();
      gp->problem.SetManifold(p + 3, &gp->quaternion_manifold);
      if (ctx.fixed[n]) {
        gp->problem.SetParameterBlockConstant(p);
        gp->problem.SetParameterBlockConstant(p + 3);
      }
    }
  }
  return gp;
}

double Cost(GraphProblem& gp) {
  double cost = 0.0;
  if (gp.problem.NumResidualBlocks() > 0) {
    gp.problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
  }
  return cost;
}

/// Solves `gp` in place and accumulates into `result`. Returns false when Ceres has no usable solution. A stage
/// that is only a starting point (the warm start) does not need to converge: `must_converge` = false.
bool RunSolve(const PoseGraphConfig& config, const std::string& stage, bool must_converge, GraphProblem* gp,
              PoseGraphResult* result) {
  ++result->num_solves;
  if (gp->problem.NumResidualBlocks() == 0) {  // nothing to solve (no edges): trivially converged
    result->final_cost = 0.0;
    return true;
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = config.max_iterations;
  options.function_tolerance = config.function_tolerance;
  options.num_threads = config.num_threads;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &gp->problem, &summary);
  result->iterations += summary.num_successful_steps + summary.num_unsuccessful_steps;
  result->final_cost = summary.final_cost;
  if (!summary.IsSolutionUsable()) {
    result->converged = false;
    result->message = "pose graph: " + stage + ": Ceres found no usable solution (poses unchanged): " +
                      summary.BriefReport();
    return false;
  }
  if (must_converge && summary.termination_type != ceres::CONVERGENCE) {
    result->converged = false;
    result->message = "pose graph: " + stage + " did not converge: " + summary.BriefReport();
  }
  return true;
}

/// Adds to `rejected` every loop edge not yet in it whose chi2 at the current params exceeds the threshold.
/// Returns whether any was added.
bool RejectLoops(const SolveContext& ctx, std::unordered_set<size_t>* rejected) {
  bool added = false;
  for (size_t k = 0; k < ctx.edges.size(); ++k) {
    const PoseGraphEdge& edge = ctx.edges[k];
    if (edge.kind != EdgeKind::kLoop || rejected->count(k) != 0) continue;
    const Vector6d e = RelativePoseError(FromParams(ctx.params[ctx.from_index[k]]),
                                         FromParams(ctx.params[ctx.to_index[k]]), edge.T_from_to);
    if (e.dot(edge.information * e) > ctx.config.loop_rejection_chi2) {
      rejected->insert(k);
      added = true;
    }
  }
  return added;
}

bool Redescending(LoopLossKind kind) { return kind == LoopLossKind::kCauchy || kind == LoopLossKind::kTukey; }

}  // namespace

PoseGraphResult PoseGraph::Optimize() {
  PoseGraphResult result;
  std::string error;
  if (!config_.Validate(&error)) {
    result.message = "pose graph: invalid config: " + error;
    return result;
  }
  if (nodes_.empty()) {
    result.message = "pose graph: no nodes";
    return result;
  }
  SolveContext ctx{config_, edges_, sqrt_information_, {}, {}, {}, {}};
  for (const Node& n : nodes_) {
    ctx.params.push_back(ToParams(n.T_world_node));
    ctx.fixed.push_back(IsFixed(n.id));
  }
  for (const PoseGraphEdge& e : edges_) {
    ctx.from_index.push_back(index_of_.at(e.from_id));
    ctx.to_index.push_back(index_of_.at(e.to_id));
  }
  const auto start = std::chrono::steady_clock::now();
  const auto finish = [&]() {
    result.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
  };
  result.converged = true;
  std::unordered_set<size_t> rejected;
  std::unique_ptr<GraphProblem> main = BuildProblem(ctx, config_.loop_loss, rejected);
  result.initial_cost = Cost(*main);
  if (config_.huber_warm_start && Redescending(config_.loop_loss)) {
    const std::unique_ptr<GraphProblem> warm = BuildProblem(ctx, LoopLossKind::kHuber, rejected);
    if (!RunSolve(config_, "huber warm start", false, warm.get(), &result)) return finish();
  }
  if (!RunSolve(config_, "robust solve", true, main.get(), &result)) return finish();
  for (int round = 1; round <= config_.max_resolve_rounds; ++round) {
    if (!RejectLoops(ctx, &rejected) || !config_.resolve_without_rejected) break;
    main = BuildProblem(ctx, config_.loop_loss, rejected);
    if (!RunSolve(config_, "re-solve " + std::to_string(round), true, main.get(), &result)) return finish();
  }
  RejectLoops(ctx, &rejected);  // after the last solve (a no-op when the loop above ended on no new rejection)
  WriteBack(ctx.params, ctx.fixed, main->in_problem);
  ReportLoops(rejected, &result);
  return finish();
}

void PoseGraph::WriteBack(const std::vector<std::array<double, 7>>& params, const std::vector<bool>& fixed,
                          const std::vector<bool>& in_problem) {
  // Nodes outside the last problem (no edges, or only rejected loops) keep their input pose bit for bit.
  for (size_t n = 0; n < nodes_.size(); ++n) {
    if (!fixed[n] && in_problem[n]) nodes_[n].T_world_node = FromParams(params[n]);
  }
}

void PoseGraph::ReportLoops(const std::unordered_set<size_t>& rejected, PoseGraphResult* result) const {
  for (size_t k = 0; k < edges_.size(); ++k) {
    const PoseGraphEdge& edge = edges_[k];
    if (edge.kind != EdgeKind::kLoop) continue;
    const Vector6d e = RelativePoseError(Pose(edge.from_id), Pose(edge.to_id), edge.T_from_to);
    const bool is_rejected = rejected.count(k) != 0;
    result->loops.push_back({k, edge.from_id, edge.to_id, e.dot(edge.information * e), is_rejected});
    (is_rejected ? result->rejected_loop_edges : result->accepted_loop_edges).push_back(k);
  }
}

// ---------------------------------------------------------------------------------------- trajectory correction

namespace {

/// C_k T (the pose rigidly corrected by keyframe k), or T itself, untouched, when keyframe k did not move.
Pose3 CorrectBy(const KeyframeCorrection& kf, const Pose3& T_world_body) {
  if (kf.T_world_kf_new.matrix() == kf.T_world_kf_old.matrix()) return T_world_body;
  return kf.T_world_kf_new * (kf.T_world_kf_old.inverse() * T_world_body);
}

Pose3 CorrectOne(const std::vector<KeyframeCorrection>& kfs, CorrectionMode mode, const StampedPose& pose) {
  // First keyframe with t_k > t: its predecessor is the nearest preceding keyframe.
  const auto upper = std::upper_bound(kfs.begin(), kfs.end(), pose.t_s,
                                      [](double t, const KeyframeCorrection& kf) { return t < kf.t_s; });
  if (upper == kfs.begin()) return CorrectBy(kfs.front(), pose.T_ref_body);
  const KeyframeCorrection& before = *(upper - 1);
  if (mode == CorrectionMode::kPrecedingKeyframe || upper == kfs.end()) return CorrectBy(before, pose.T_ref_body);
  const KeyframeCorrection& after = *upper;  // after.t_s > pose.t_s >= before.t_s
  const Pose3 A = CorrectBy(before, pose.T_ref_body), B = CorrectBy(after, pose.T_ref_body);
  if (A.matrix() == pose.T_ref_body.matrix() && B.matrix() == pose.T_ref_body.matrix()) return pose.T_ref_body;
  return Interpolate(A, B, (pose.t_s - before.t_s) / (after.t_s - before.t_s));
}

}  // namespace

Status CorrectTrajectory(const std::vector<KeyframeCorrection>& keyframes, CorrectionMode mode,
                         Trajectory* trajectory) {
  if (keyframes.empty()) return Status::Error("CorrectTrajectory: no keyframes");
  for (size_t i = 0; i < trajectory->size(); ++i) {
    if (!std::isfinite((*trajectory)[i].t_s)) {
      return Status::Error("CorrectTrajectory: trajectory pose " + std::to_string(i) + ": t_s is not finite");
    }
  }
  for (size_t k = 0; k < keyframes.size(); ++k) {
    const KeyframeCorrection& kf = keyframes[k];
    const std::string name = "CorrectTrajectory: keyframe " + std::to_string(k);
    if (!std::isfinite(kf.t_s)) return Status::Error(name + ": t_s is not finite");
    if (k > 0 && kf.t_s < keyframes[k - 1].t_s) {
      return Status::Error(name + ": t_s earlier than keyframe " + std::to_string(k - 1) + "'s (unsorted)");
    }
    if (!IsValidPose(kf.T_world_kf_old) || !IsValidPose(kf.T_world_kf_new)) {
      return Status::Error(name + ": pose is not finite or not a rotation");
    }
  }
  for (StampedPose& pose : *trajectory) pose.T_ref_body = CorrectOne(keyframes, mode, pose);
  return Status::Ok();
}

}  // namespace rotolidar::graph
