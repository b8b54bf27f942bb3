#include "core/registration/scan_to_map.hpp"

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

/// Correspondences of every scan edge and planar point at the pose T_map_scan.
Matches FindMatches(const FeatureSet& scan, const LocalMap& map, const Pose3& T_map_scan, const ScanToMapConfig& c) {
  Matches m;
  const float max_sq = float(c.max_neighbour_distance_m * c.max_neighbour_distance_m);
  std::vector<Eigen::Vector3d> nbrs;
  std::vector<float> sq;
  for (const auto& pt : scan.edge.points) {
    const Eigen::Vector3d p_scan(pt.x, pt.y, pt.z);
    if (map.Nearest(FeatureKind::kEdge, T_map_scan * p_scan, c.num_neighbours, &nbrs, &sq) < c.num_neighbours ||
        sq.back() > max_sq)
      continue;
    EdgeMatch e{p_scan, {}, {}};
    if (FitLine(nbrs, c.min_line_eigen_ratio, &e.a_map, &e.u_map)) m.edges.push_back(e);
  }
  for (const auto& pt : scan.planar.points) {
    const Eigen::Vector3d p_scan(pt.x, pt.y, pt.z);
    if (map.Nearest(FeatureKind::kPlanar, T_map_scan * p_scan, c.num_neighbours, &nbrs, &sq) < c.num_neighbours ||
        sq.back() > max_sq)
      continue;
    PlaneMatch p{p_scan, {}, 0.0};
    if (FitPlane(nbrs, c.max_plane_eigen_ratio, c.max_plane_deviation_m, &p.n_map, &p.d_m)) m.planes.push_back(p);
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

/// One outer loop from `guess`. With num_degenerate > 0, every update is remapped: its components along the
/// num_degenerate weakest eigen-directions of the current linearisation are removed.
ScanToMapResult Solve(const FeatureSet& scan, const LocalMap& map, const Pose3& guess, const ScanToMapConfig& config,
                      int num_degenerate) {
  ScanToMapResult result;
  result.T_map_scan = guess;
  PoseParameters x;
  std::unique_ptr<MatchProblem> problem;
  Matches matches;
  for (int it = 0; it < config.max_correspondence_rebuilds; ++it) {
    matches = FindMatches(scan, map, result.T_map_scan, config);
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
  ScanToMapResult full = Solve(scan, map, T_map_scan_guess, config, 0);
  if (!config.degeneracy.remap || !full.degeneracy.degenerate) return full;
  // Phase 2 (Zhang et al.'s solution remapping): solve again from the guess with every update projected onto
  // the well-observed subspace, so the degenerate directions keep the guess (the prior / IMU's value).
  ScanToMapResult remapped =
      Solve(scan, map, T_map_scan_guess, config, int(full.degeneracy.degenerate_directions.size()));
  remapped.remapped = true;
  remapped.iterations += full.iterations;
  remapped.solver_iterations += full.solver_iterations;
  return remapped;
}

}  // namespace rotolidar
