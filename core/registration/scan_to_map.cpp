#include "core/registration/scan_to_map.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include <ceres/ceres.h>
#include <Eigen/Eigenvalues>

#include "core/registration/residuals.hpp"
#include "core/util/log.hpp"

namespace rotolidar {
namespace {

struct EdgeMatch {
  Eigen::Vector3d p_scan, a_map, u_map;
};
struct PlaneMatch {
  Eigen::Vector3d p_scan, n_map;
  double d_m;
};
struct Matches {
  std::vector<EdgeMatch> edges;
  std::vector<PlaneMatch> planes;
  size_t size() const { return edges.size() + planes.size(); }
};

/// Mean and covariance of a small point set.
void MeanCovariance(const std::vector<Eigen::Vector3d>& points, Eigen::Vector3d* mean, Eigen::Matrix3d* cov) {
  *mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) *mean += p;
  *mean /= double(points.size());
  cov->setZero();
  for (const auto& p : points) *cov += (p - *mean) * (p - *mean).transpose();
  *cov /= double(points.size());
}

/// A scan point's last neighbour search. Its k nearest map points stay the k nearest while the query moves less
/// than half the gap between the k-th and (k+1)-th distance (triangle inequality), so the rebuilds of one
/// registration (the outer iterations converge in mm steps; the remapped solve restarts at the guess) reuse the
/// set and its line / plane fit instead of searching the kd-tree again. Exact up to distance ties (never reused).
struct NeighbourSet {
  enum class Fit { kUnknown, kAccepted, kRejected };
  bool searched = false;
  Eigen::Vector3d q_map = Eigen::Vector3d::Zero();  ///< where the set was searched (map frame)
  double reuse_radius_m = -1.0;                     ///< the set is exact within this distance of q_map (< 0: never)
  std::vector<Eigen::Vector3d> points;              ///< the k nearest, nearest first (fewer: a sparse map)
  Fit fit = Fit::kUnknown;
  Eigen::Vector3d a_or_n = Eigen::Vector3d::Zero();  ///< line point (edge) or plane normal (planar)
  Eigen::Vector3d u = Eigen::Vector3d::Zero();       ///< line direction (edge)
  double d_m = 0.0;                                  ///< plane offset (planar)
};

/// The neighbour sets of one scan's features, shared by every FindMatches of one Register call.
struct MatchCache {
  std::vector<NeighbourSet> edges, planes;
};

/// Kd-tree distances are float: the reuse radius keeps this margin against their rounding [m].
constexpr double kReuseMarginM = 1e-5;

/// Squared distance of the k-th neighbour of q_map: the search's own value, or recomputed for a reused set.
/// Searches again (and forgets the fit) unless q_map lies within the set's reuse radius.
double KthSquaredDistance(const LocalMap& map, FeatureKind kind, const Eigen::Vector3d& q_map, int k,
                          NeighbourSet* set) {
  if (set->searched && (q_map - set->q_map).norm() <= set->reuse_radius_m) {
    double max_sq = 0.0;
    for (const Eigen::Vector3d& p : set->points) max_sq = std::max(max_sq, (p - q_map).squaredNorm());
    return max_sq;
  }
  thread_local std::vector<float> sq;
  const int found = map.Nearest(kind, q_map, k + 1, &set->points, &sq);
  set->searched = true;
  set->q_map = q_map;
  set->fit = NeighbourSet::Fit::kUnknown;
  set->reuse_radius_m = -1.0;
  if (found == k + 1) {
    const double gap_m = std::sqrt(double(sq[size_t(k)])) - std::sqrt(double(sq[size_t(k - 1)]));
    set->reuse_radius_m = 0.5 * gap_m - kReuseMarginM;
  }
  if (found > k) set->points.resize(size_t(k));
  return found >= k ? sq[size_t(k - 1)] : 0.0;
}

/// Correspondences of every scan edge and planar point at the pose T_map_scan (neighbour sets from *cache where
/// still exact).
Matches FindMatches(const FeatureSet& scan, const LocalMap& map, const Pose3& T_map_scan, const ScanToMapConfig& c,
                    MatchCache* cache) {
  using Fit = NeighbourSet::Fit;
  Matches m;
  const int k = c.num_neighbours;
  const float max_sq = float(c.max_neighbour_distance_m * c.max_neighbour_distance_m);
  cache->edges.resize(scan.edge.points.size());
  cache->planes.resize(scan.planar.points.size());
  for (size_t i = 0; i < scan.edge.points.size(); ++i) {
    const auto& pt = scan.edge.points[i];
    const Eigen::Vector3d p_scan(pt.x, pt.y, pt.z);
    NeighbourSet& s = cache->edges[i];
    const double kth_sq = KthSquaredDistance(map, FeatureKind::kEdge, T_map_scan * p_scan, k, &s);
    if (int(s.points.size()) < k || kth_sq > max_sq) continue;
    if (s.fit == Fit::kUnknown)
      s.fit = FitLine(s.points, c.min_line_eigen_ratio, &s.a_or_n, &s.u) ? Fit::kAccepted : Fit::kRejected;
    if (s.fit == Fit::kAccepted) m.edges.push_back({p_scan, s.a_or_n, s.u});
  }
  for (size_t i = 0; i < scan.planar.points.size(); ++i) {
    const auto& pt = scan.planar.points[i];
    const Eigen::Vector3d p_scan(pt.x, pt.y, pt.z);
    NeighbourSet& s = cache->planes[i];
    const double kth_sq = KthSquaredDistance(map, FeatureKind::kPlanar, T_map_scan * p_scan, k, &s);
    if (int(s.points.size()) < k || kth_sq > max_sq) continue;
    if (s.fit == Fit::kUnknown)
      s.fit = FitPlane(s.points, c.max_plane_eigen_ratio, c.max_plane_deviation_m, &s.a_or_n, &s.d_m)
                  ? Fit::kAccepted
                  : Fit::kRejected;
    if (s.fit == Fit::kAccepted) m.planes.push_back({p_scan, s.a_or_n, s.d_m});
  }
  return m;
}

/// The displacement metric (degeneracy.hpp) of the matched points at pose T: lever arms R p_scan.
Matrix6d MetricOf(const Matches& m, const Pose3& T) {
  std::vector<Eigen::Vector3d> levers;
  levers.reserve(m.size());
  for (const auto& e : m.edges) levers.push_back(T.linear() * e.p_scan);
  for (const auto& p : m.planes) levers.push_back(T.linear() * p.p_scan);
  return DisplacementMetric(levers);
}

ceres::LossFunction* MakeLoss(const ScanToMapConfig& c) {
  switch (c.loss) {
    case RobustLoss::kHuber: return new ceres::HuberLoss(c.loss_scale_m);
    case RobustLoss::kCauchy: return new ceres::CauchyLoss(c.loss_scale_m);
    case RobustLoss::kNone: break;
  }
  return nullptr;
}

/// One Ceres problem over the pose block `x` for a fixed correspondence set. Owns its loss and manifold.
class MatchProblem {
 public:
  MatchProblem(const Matches& m, const ScanToMapConfig& c, double* x) : loss_(MakeLoss(c)) {
    ceres::Problem::Options options;
    options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem_ = std::make_unique<ceres::Problem>(options);
    problem_->AddParameterBlock(x, 7, &manifold_);
    for (const auto& e : m.edges)
      problem_->AddResidualBlock(new PointToLineResidual(e.p_scan, e.a_map, e.u_map), loss_.get(), x);
    for (const auto& p : m.planes)
      problem_->AddResidualBlock(new PointToPlaneResidual(p.p_scan, p.n_map, p.d_m), loss_.get(), x);
  }

  /// Solves in place; returns the Ceres summary.
  ceres::Solver::Summary Solve(const ScanToMapConfig& c) {
    ceres::Solver::Options options;
    options.linear_solver_type = ceres::DENSE_QR;
    options.max_num_iterations = c.max_solver_iterations;
    options.num_threads = c.num_threads;
    options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(options, problem_.get(), &summary);
    return summary;
  }

  const ceres::LossFunction* loss() const { return loss_.get(); }

 private:
  std::unique_ptr<ceres::LossFunction> loss_;
  PoseManifold manifold_;
  std::unique_ptr<ceres::Problem> problem_;
};

struct Evaluation {
  double cost = 0.0;  ///< 1/2 sum rho(|r|^2), as Ceres reports it [m^2]
  double rmse_m = 0.0;
  Matrix6d hessian = Matrix6d::Zero();
};

/// Cost, RMS residual and the IRLS-weighted Gauss-Newton Hessian sum rho'(|r|^2) J^T J in the tangent
/// [dt; dtheta] (residuals.hpp), at pose T. Independent of Ceres' own (half-angle) quaternion tangent.
Evaluation Evaluate(const Matches& m, const Pose3& T, const ceres::LossFunction* loss) {
  Evaluation e;
  double sum_sq = 0.0;
  auto add = [&](double s, const auto& J) {
    double rho[3] = {s, 1.0, 0.0};
    if (loss != nullptr) loss->Evaluate(s, rho);
    e.cost += 0.5 * rho[0];
    e.hessian += rho[1] * J.transpose() * J;
    sum_sq += s;
  };
  Eigen::Matrix<double, 1, 6> J1;
  Eigen::Matrix<double, 2, 6> J2;
  for (const auto& p : m.planes) {
    const double r = PointToPlaneResidual(p.p_scan, p.n_map, p.d_m).EvaluateTangent(T, &J1);
    add(r * r, J1);
  }
  for (const auto& l : m.edges) {
    const Eigen::Vector2d r = PointToLineResidual(l.p_scan, l.a_map, l.u_map).EvaluateTangent(T, &J2);
    add(r.squaredNorm(), J2);
  }
  e.rmse_m = m.size() ? std::sqrt(sum_sq / double(m.size())) : 0.0;
  return e;
}

}  // namespace

bool ScanToMapConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (max_solver_iterations < 1) return fail("scan_to_map.max_solver_iterations must be >= 1");
  if (max_correspondence_rebuilds < 1) return fail("scan_to_map.max_correspondence_rebuilds must be >= 1");
  if (num_neighbours < 3) return fail("scan_to_map.num_neighbours must be >= 3 (a plane needs 3 points)");
  if (!(max_neighbour_distance_m > 0)) return fail("scan_to_map.max_neighbour_distance_m must be > 0");
  if (!(min_line_eigen_ratio > 1)) return fail("scan_to_map.min_line_eigen_ratio must be > 1");
  if (!(max_plane_eigen_ratio > 0 && max_plane_eigen_ratio < 1))
    return fail("scan_to_map.max_plane_eigen_ratio must be in (0, 1)");
  if (!(max_plane_deviation_m > 0)) return fail("scan_to_map.max_plane_deviation_m must be > 0");
  if (loss != RobustLoss::kNone && !(loss_scale_m > 0)) return fail("scan_to_map.loss_scale_m must be > 0");
  if (!(convergence_translation_m > 0)) return fail("scan_to_map.convergence_translation_m must be > 0");
  if (!(convergence_rotation_rad > 0)) return fail("scan_to_map.convergence_rotation_rad must be > 0");
  if (min_correspondences < 6) return fail("scan_to_map.min_correspondences must be >= 6 (6 pose unknowns)");
  if (num_threads < 1) return fail("scan_to_map.num_threads must be >= 1");
  return degeneracy.Validate(error);
}

bool FitLine(const std::vector<Eigen::Vector3d>& points, double min_ratio, Eigen::Vector3d* point,
             Eigen::Vector3d* direction) {
  if (points.size() < 2) return false;
  Eigen::Matrix3d cov;
  MeanCovariance(points, point, &cov);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);  // ascending
  if (!(eig.eigenvalues()(2) > 0.0) || eig.eigenvalues()(2) < min_ratio * eig.eigenvalues()(1)) return false;
  *direction = eig.eigenvectors().col(2).normalized();
  return true;
}

bool FitPlane(const std::vector<Eigen::Vector3d>& points, double max_ratio, double max_deviation_m,
              Eigen::Vector3d* normal, double* d_m) {
  if (points.size() < 3) return false;
  Eigen::Vector3d mean;
  Eigen::Matrix3d cov;
  MeanCovariance(points, &mean, &cov);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  if (!(eig.eigenvalues()(1) > 0.0) || eig.eigenvalues()(0) > max_ratio * eig.eigenvalues()(1)) return false;
  *normal = eig.eigenvectors().col(0).normalized();
  *d_m = -normal->dot(mean);
  for (const auto& p : points)
    if (std::abs(normal->dot(p) + *d_m) > max_deviation_m) return false;
  return true;
}

namespace {

/// One outer loop from `guess` (neighbour sets kept in *cache). With num_degenerate > 0, every update is
/// remapped: its components along the num_degenerate weakest eigen-directions of the current linearisation are
/// removed.
ScanToMapResult Solve(const FeatureSet& scan, const LocalMap& map, const Pose3& guess, const ScanToMapConfig& config,
                      int num_degenerate, MatchCache* cache) {
  ScanToMapResult result;
  result.T_map_scan = guess;
  PoseParameters x;
  std::unique_ptr<MatchProblem> problem;
  Matches matches;
  for (int it = 0; it < config.max_correspondence_rebuilds; ++it) {
    matches = FindMatches(scan, map, result.T_map_scan, config, cache);
    if (int(matches.size()) < config.min_correspondences) {
      result.message = "only " + std::to_string(matches.size()) + " correspondences at outer iteration " +
                       std::to_string(it) + " (min_correspondences = " + std::to_string(config.min_correspondences) +
                       ")";
      problem.reset();
      break;
    }
    x = PoseToParameters(result.T_map_scan);
    problem = std::make_unique<MatchProblem>(matches, config, x.data());
    const ceres::Solver::Summary summary = problem->Solve(config);
    if (it == 0) result.initial_cost = summary.initial_cost;
    result.solver_iterations += int(summary.iterations.size());
    result.iterations = it + 1;
    const Pose3 solved = ParametersToPose(x.data());
    Vector6d delta = PoseBoxMinus(solved, result.T_map_scan);
    if (num_degenerate > 0) {  // re-linearised every iteration: the weak directions turn with the rotation
      const Evaluation e = Evaluate(matches, solved, problem->loss());
      const DegeneracyInfo here =
          AnalyzeDegeneracy(e.hessian, MetricOf(matches, solved), int(matches.size()), config.degeneracy);
      delta = ProjectionWithout(here, num_degenerate) * delta;
    }
    result.T_map_scan = PoseBoxPlus(result.T_map_scan, delta);
    if (delta.head<3>().norm() < config.convergence_translation_m &&
        delta.tail<3>().norm() < config.convergence_rotation_rad) {
      result.converged = true;
      break;
    }
  }
  if (!problem) return result;
  // Report at the final pose with the last correspondence set.
  const Evaluation final_eval = Evaluate(matches, result.T_map_scan, problem->loss());
  result.final_cost = final_eval.cost;
  result.rmse_m = final_eval.rmse_m;
  result.hessian = final_eval.hessian;
  result.edge_inliers = int(matches.edges.size());
  result.planar_inliers = int(matches.planes.size());
  result.degeneracy = AnalyzeDegeneracy(result.hessian, MetricOf(matches, result.T_map_scan), int(matches.size()),
                                        config.degeneracy);
  if (!result.converged && result.message.empty())
    result.message = "no convergence in " + std::to_string(config.max_correspondence_rebuilds) + " rebuilds";
  return result;
}

}  // namespace

ScanToMapResult Register(const FeatureSet& scan, const LocalMap& map, const Pose3& T_map_scan_guess,
                         const ScanToMapConfig& config) {
  std::string error;
  ROTOLIDAR_CHECK(config.Validate(&error), error);
  // Phase 1: the full solve. Its converged correspondences tell which directions the scene observes; deciding
  // that at the guess instead (as LOAM does at its first iteration) misjudges a far guess (KITTI 0->1 from
  // identity, 0.7 m off, looks degenerate there and would freeze the very direction it has to move along).
  MatchCache cache;
  ScanToMapResult full = Solve(scan, map, T_map_scan_guess, config, 0, &cache);
  if (!config.degeneracy.remap || !full.degeneracy.degenerate) return full;
  // Phase 2 (Zhang et al.'s solution remapping): solve again from the guess with every update projected onto
  // the well-observed subspace, so the degenerate directions keep the guess (the prior / IMU's value).
  ScanToMapResult remapped =
      Solve(scan, map, T_map_scan_guess, config, int(full.degeneracy.degenerate_directions.size()), &cache);
  remapped.remapped = true;
  remapped.iterations += full.iterations;
  remapped.solver_iterations += full.solver_iterations;
  return remapped;
}

}  // namespace rotolidar
