#include "core/registration/scan_to_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <ceres/ceres.h>

#include "core/registration/match_problem.hpp"
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
  double weight;  ///< incidence weight (PointToPlaneResidual)
};
struct Matches {
  std::vector<EdgeMatch> edges;
  std::vector<PlaneMatch> planes;
  size_t size() const { return edges.size() + planes.size(); }
};

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
  std::vector<Eigen::Vector3f> views;               ///< their mean unit view vectors (LocalMap::Nearest)
  bool has_next = false;                            ///< the search also found a (k+1)-th point:
  Eigen::Vector3d next = Eigen::Vector3d::Zero();   ///< ... this one (bounds the next search, KthSquaredDistance)
  Fit fit = Fit::kUnknown;
  Eigen::Vector3d a_or_n = Eigen::Vector3d::Zero();  ///< line point (edge) or plane normal (planar)
  Eigen::Vector3d u = Eigen::Vector3d::Zero();       ///< line direction (edge)
  double d_m = 0.0;                                  ///< plane offset (planar)
};

/// The neighbour sets of one scan's features, shared by every FindMatches of one Register call.
struct MatchCache {
  std::vector<NeighbourSet> edges, planes;
  int searches = 0;  ///< map searches since Reset (reused sets not counted)
  /// Forgets every search (a set's vectors keep their capacity: no per-point allocation per registration).
  void Reset(size_t num_edges, size_t num_planes) {
    edges.resize(num_edges);
    planes.resize(num_planes);
    for (auto* sets : {&edges, &planes})
      for (NeighbourSet& s : *sets) s.searched = s.has_next = false;
    searches = 0;
  }
};

/// This thread's cache (Register is re-entrant per thread), reset for `scan`.
MatchCache& ThreadMatchCache(const FeatureSet& scan) {
  thread_local MatchCache cache;
  cache.Reset(scan.edge.points.size(), scan.planar.points.size());
  return cache;
}

/// Kd-tree distances are float: the reuse radius keeps this margin against their rounding [m].
constexpr double kReuseMarginM = 1e-5;

/// Squared distance of the k-th neighbour of q_map: the search's own value, or recomputed for a reused set.
/// Searches again (and forgets the fit) unless q_map lies within the set's reuse radius.
/// The search is bounded: only neighbours with squared distance < bound_sq count (bound_sq just above the
/// acceptance limit), so a set with fewer than k is rejected exactly as an unbounded one with a far k-th would
/// be, and a (k+1)-th beyond the bound is taken at the bound (a smaller, still exact, reuse radius).
double KthSquaredDistance(const LocalMap& map, FeatureKind kind, const Eigen::Vector3d& q_map, int k,
                          float bound_sq, double reuse_m, NeighbourSet* set, int* searches) {
  if (set->searched && (q_map - set->q_map).norm() <= std::max(set->reuse_radius_m, reuse_m)) {
    double max_sq = 0.0;
    for (const Eigen::Vector3d& p : set->points) max_sq = std::max(max_sq, (p - q_map).squaredNorm());
    return max_sq;
  }
  // The last k + 1 points bound the new (k+1)-th distance (float, as the tree computes it): searching just
  // above it returns the same neighbours, skipping only points that could never make the result.
  float search_sq = bound_sq;
  if (set->has_next) {
    const float q[3] = {float(q_map.x()), float(q_map.y()), float(q_map.z())};
    auto tree_sq = [&q](const Eigen::Vector3d& p) {
      const float dx = q[0] - float(p.x()), dy = q[1] - float(p.y()), dz = q[2] - float(p.z());
      return dx * dx + dy * dy + dz * dz;
    };
    float farthest = tree_sq(set->next);
    for (const Eigen::Vector3d& p : set->points) farthest = std::max(farthest, tree_sq(p));
    search_sq = std::min(bound_sq, std::nextafter(farthest, std::numeric_limits<float>::infinity()));
  }
  thread_local std::vector<float> sq;
  const int found = map.Nearest(kind, q_map, k + 1, &set->points, &sq, search_sq, &set->views);
  ++*searches;
  set->searched = true;
  set->q_map = q_map;
  set->fit = NeighbourSet::Fit::kUnknown;
  set->reuse_radius_m = -1.0;
  if (found >= k) {
    const double next_sq = found == k + 1 ? double(sq[size_t(k)]) : double(bound_sq);
    const double gap_m = std::sqrt(next_sq) - std::sqrt(double(sq[size_t(k - 1)]));
    set->reuse_radius_m = 0.5 * gap_m - kReuseMarginM;
  }
  set->has_next = found > k;
  if (found > k) {
    set->next = set->points[size_t(k)];
    set->points.resize(size_t(k));
    set->views.resize(size_t(k));
  }
  return found >= k ? sq[size_t(k - 1)] : 0.0;
}

/// |cos| below which a view counts as grazing: it does not tell which side of a plane it came from.
constexpr double kGrazingCos = 0.05;

/// The plane fit of a neighbour set, respecting which side of the surface the map saw it from: neighbours seen
/// from the other side than the scan point sees it (n . view of opposite signs: a thin wall's back face, first
/// seen through a door, next to the front face in the map) are dropped and the plane refit from the rest; fewer
/// than half the set left rejects the match. view_scan: scan point -> sensor (map frame). The decision is made
/// when the set is (re)searched and cached with its fit (the side of a non-grazing view does not flip within
/// the reuse radius of a converging registration).
bool FitVisiblePlane(const Eigen::Vector3d& view_scan, const ScanToMapConfig& c, NeighbourSet* s) {
  if (!FitPlane(s->points, c.max_plane_eigen_ratio, c.max_plane_deviation_m, &s->a_or_n, &s->d_m)) return false;
  const double side_scan = s->a_or_n.dot(view_scan.normalized());
  if (!c.visibility_check || std::abs(side_scan) < kGrazingCos) return true;
  thread_local std::vector<Eigen::Vector3d> same_side;
  same_side.clear();
  for (size_t i = 0; i < s->points.size(); ++i) {
    const double side = s->a_or_n.dot(s->views[i].cast<double>());
    if (side * side_scan >= 0 || std::abs(side) < kGrazingCos) same_side.push_back(s->points[i]);
  }
  if (same_side.size() == s->points.size()) return true;
  if (2 * same_side.size() < s->points.size()) return false;
  return FitPlane(same_side, c.max_plane_eigen_ratio, c.max_plane_deviation_m, &s->a_or_n, &s->d_m);
}

/// The weight of a plane match (ScanToMapConfig::plane_incidence_exponent): max(|cos incidence|, min_cos)^k, the
/// incidence between the plane's normal and the ray from the scan frame's origin (the base at the scan start;
/// the sensor sits within the rotor's lever arm of it) to the point.
double IncidenceWeight(const Pose3& T_map_scan, const Eigen::Vector3d& p_scan, const Eigen::Vector3d& n_map,
                       const ScanToMapConfig& c) {
  if (c.plane_incidence_exponent == 0.0) return 1.0;
  const Eigen::Vector3d ray_map = T_map_scan.linear() * p_scan;
  const double cos_incidence = std::abs(n_map.dot(ray_map)) / std::max(ray_map.norm(), 1e-9);
  return std::pow(std::max(cos_incidence, c.plane_incidence_min_cos), c.plane_incidence_exponent);
}

/// Correspondences of every scan edge and planar point at the pose T_map_scan (neighbour sets from *cache where
/// still exact).
/// For each point of one feature class: its k map neighbours (reused while the point stays within
/// neighbour_reuse_m), a local fit decided once per neighbour set (`fit`: true = accepted), and `emit` for each
/// accepted one. Points with fewer than k neighbours within max_neighbour_distance_m are skipped.
template <class Points, class FitFn, class EmitFn>
void MatchClass(const Points& points, FeatureKind kind, const LocalMap& map, const Pose3& T_map_scan,
                const ScanToMapConfig& c, std::vector<NeighbourSet>* sets, int* searches, FitFn fit, EmitFn emit) {
  using Fit = NeighbourSet::Fit;
  const int k = c.num_neighbours;
  const float max_sq = float(c.max_neighbour_distance_m * c.max_neighbour_distance_m);
  const float bound_sq = std::nextafter(max_sq, std::numeric_limits<float>::infinity());  // k-th == max passes
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d p_scan(points[i].x, points[i].y, points[i].z);
    NeighbourSet& s = (*sets)[i];
    const double kth_sq =
        KthSquaredDistance(map, kind, T_map_scan * p_scan, k, bound_sq, c.neighbour_reuse_m, &s, searches);
    if (int(s.points.size()) < k || kth_sq > max_sq) continue;
    if (s.fit == Fit::kUnknown) s.fit = fit(&s) ? Fit::kAccepted : Fit::kRejected;
    if (s.fit == Fit::kAccepted) emit(p_scan, s);
  }
}

Matches FindMatches(const FeatureSet& scan, const LocalMap& map, const Pose3& T_map_scan, const ScanToMapConfig& c,
                    MatchCache* cache) {
  Matches m;
  MatchClass(
      scan.edge.points, FeatureKind::kEdge, map, T_map_scan, c, &cache->edges, &cache->searches,
      [&](NeighbourSet* s) { return FitLine(s->points, c.min_line_eigen_ratio, &s->a_or_n, &s->u); },
      [&](const Eigen::Vector3d& p, const NeighbourSet& s) { m.edges.push_back({p, s.a_or_n, s.u}); });
  MatchClass(
      scan.planar.points, FeatureKind::kPlanar, map, T_map_scan, c, &cache->planes, &cache->searches,
      [&](NeighbourSet* s) { return FitVisiblePlane(T_map_scan.translation() - s->q_map, c, s); },
      [&](const Eigen::Vector3d& p, const NeighbourSet& s) {
        m.planes.push_back({p, s.a_or_n, s.d_m, IncidenceWeight(T_map_scan, p, s.a_or_n, c)});
      });
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

/// Loads m into *problem (one residual block per match) and solves it from *T (in place). Returns the summary.
ceres::Solver::Summary SolveMatches(const Matches& m, MatchProblem* problem, Pose3* T) {
  problem->Resize(m.edges.size(), m.planes.size());
  for (size_t i = 0; i < m.edges.size(); ++i) {
    const EdgeMatch& e = m.edges[i];
    problem->SetLine(i, e.p_scan, e.a_map, e.u_map);
  }
  for (size_t i = 0; i < m.planes.size(); ++i) {
    const PlaneMatch& p = m.planes[i];
    problem->SetPlane(i, p.p_scan, p.n_map, p.d_m, p.weight);
  }
  return problem->Solve(T);
}

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
    const double r = PointToPlaneResidual(p.p_scan, p.n_map, p.d_m, p.weight).EvaluateTangent(T, &J1);
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
  if (!(neighbour_reuse_m >= 0)) return fail("scan_to_map.neighbour_reuse_m must be >= 0");
  if (num_neighbours >= LocalMap::kMaxNearest)
    return fail("scan_to_map.num_neighbours must be < " + std::to_string(LocalMap::kMaxNearest));
  if (!(max_neighbour_distance_m > 0)) return fail("scan_to_map.max_neighbour_distance_m must be > 0");
  if (!(min_line_eigen_ratio > 1)) return fail("scan_to_map.min_line_eigen_ratio must be > 1");
  if (!(max_plane_eigen_ratio > 0 && max_plane_eigen_ratio < 1))
    return fail("scan_to_map.max_plane_eigen_ratio must be in (0, 1)");
  if (!(max_plane_deviation_m > 0)) return fail("scan_to_map.max_plane_deviation_m must be > 0");
  if (!(plane_incidence_exponent >= 0 && plane_incidence_exponent <= 4))
    return fail("scan_to_map.plane_incidence_exponent must be in [0, 4]");
  if (!(plane_incidence_min_cos > 0 && plane_incidence_min_cos <= 1))
    return fail("scan_to_map.plane_incidence_min_cos must be in (0, 1]");
  if (loss != RobustLoss::kNone && !(loss_scale_m > 0)) return fail("scan_to_map.loss_scale_m must be > 0");
  if (!(convergence_translation_m > 0)) return fail("scan_to_map.convergence_translation_m must be > 0");
  if (!(convergence_rotation_rad > 0)) return fail("scan_to_map.convergence_rotation_rad must be > 0");
  if (min_correspondences < 6) return fail("scan_to_map.min_correspondences must be >= 6 (6 pose unknowns)");
  if (num_threads < 1) return fail("scan_to_map.num_threads must be >= 1");
  return degeneracy.Validate(error);
}

namespace {

/// One outer iteration: the correspondences found at T_before and the pose they solve to.
struct OuterStep {
  Pose3 T_before = Pose3::Identity();
  Pose3 T_after = Pose3::Identity();
  Matches matches;
  int solver_iterations = 0;
};

/// Solves step->matches from step->T_before into step->T_after; with num_degenerate > 0 the update is remapped
/// (its components along the num_degenerate weakest eigen-directions at the solution removed). Returns the update.
Vector6d SolveStep(const ScanToMapConfig& config, int num_degenerate, MatchProblem* problem, OuterStep* step,
                   double* initial_cost) {
  Pose3 solved = step->T_before;
  const ceres::Solver::Summary summary = SolveMatches(step->matches, problem, &solved);
  *initial_cost = summary.initial_cost;
  step->solver_iterations = int(summary.iterations.size());
  Vector6d delta = PoseBoxMinus(solved, step->T_before);
  if (num_degenerate > 0) {  // re-linearised every iteration: the weak directions turn with the rotation
    const Evaluation e = Evaluate(step->matches, solved, problem->loss());
    const DegeneracyInfo here =
        AnalyzeDegeneracy(e.hessian, MetricOf(step->matches, solved), int(step->matches.size()), config.degeneracy);
    delta = ProjectionWithout(here, num_degenerate) * delta;
  }
  step->T_after = PoseBoxPlus(step->T_before, delta);
  return delta;
}

/// Pose `a` is back at `b`: within kCycleFraction of the convergence thresholds (far below any pose change that
/// matters; an outer loop settles into a 2-cycle geometrically, ~10x closer per round, so the remaining rounds
/// would only move the result by less than this).
constexpr double kCycleFraction = 1e-3;
bool IsCycle(const Pose3& a, const Pose3& b, const ScanToMapConfig& c) {
  const Vector6d d = PoseBoxMinus(a, b);
  return d.head<3>().norm() < kCycleFraction * c.convergence_translation_m &&
         d.tail<3>().norm() < kCycleFraction * c.convergence_rotation_rad;
}

/// One outer loop from `guess` (neighbour sets kept in *cache), updates remapped when num_degenerate > 0.
/// A 2-cycle (the pose returns to where it was two rebuilds ago, IsCycle: two correspondence sets that solve into
/// each other) repeats until max_correspondence_rebuilds and never converges (both updates have the same size),
/// so it is not iterated: the result is the state the last rebuild would leave, counts included.
ScanToMapResult Solve(const FeatureSet& scan, const LocalMap& map, const Pose3& guess, const ScanToMapConfig& config,
                      int num_degenerate, MatchCache* cache, MatchProblem* problem) {
  ScanToMapResult result;
  result.T_map_scan = guess;
  const int n = config.max_correspondence_rebuilds;
  OuterStep prev, cur;  // cur: the latest outer iteration
  for (int it = 0; it < n; ++it) {
    std::swap(prev, cur);
    cur.T_before = result.T_map_scan;
    cur.matches = FindMatches(scan, map, cur.T_before, config, cache);
    if (int(cur.matches.size()) < config.min_correspondences) {
      result.message = "only " + std::to_string(cur.matches.size()) + " correspondences at outer iteration " +
                       std::to_string(it) + " (min_correspondences = " + std::to_string(config.min_correspondences) +
                       ")";
      return result;
    }
    double initial_cost = 0.0;
    const Vector6d delta = SolveStep(config, num_degenerate, problem, &cur, &initial_cost);
    if (it == 0) result.initial_cost = initial_cost;
    result.solver_iterations += cur.solver_iterations;
    result.iterations = it + 1;
    result.T_map_scan = cur.T_after;
    if (delta.head<3>().norm() < config.convergence_translation_m &&
        delta.tail<3>().norm() < config.convergence_rotation_rad) {
      result.converged = true;
      break;
    }
    if (it >= 1 && IsCycle(cur.T_after, prev.T_before, config)) {  // rebuild j > it repeats prev for odd j - it
      const int remaining = n - 1 - it;
      result.solver_iterations += (remaining + 1) / 2 * prev.solver_iterations + remaining / 2 * cur.solver_iterations;
      result.iterations = n;
      if (remaining % 2 == 1) std::swap(prev, cur);
      result.T_map_scan = cur.T_after;
      break;
    }
  }
  // Report at the final pose with the last correspondence set.
  const Matches& matches = cur.matches;
  const Evaluation final_eval = Evaluate(matches, result.T_map_scan, problem->loss());
  result.final_cost = final_eval.cost;
  result.rmse_m = final_eval.rmse_m;
  result.hessian = final_eval.hessian;
  result.edge_inliers = int(matches.edges.size());
  result.planar_inliers = int(matches.planes.size());
  result.degeneracy = AnalyzeDegeneracy(result.hessian, MetricOf(matches, result.T_map_scan), int(matches.size()),
                                        config.degeneracy);
  MarkDegenerate(num_degenerate, &result.degeneracy);  // the remapped directions, gated ones included
  if (!result.converged && result.message.empty())
    result.message = "no convergence in " + std::to_string(n) + " rebuilds";
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
  MatchCache& cache = ThreadMatchCache(scan);
  MatchProblem problem(config);  // one Ceres problem for every correspondence set of both phases
  ScanToMapResult full = Solve(scan, map, T_map_scan_guess, config, 0, &cache, &problem);
  // Degenerate directions, and weak ones whose solution strays from the guess beyond the gate.
  const int num_degenerate =
      GatedDegenerateCount(full.degeneracy, PoseBoxMinus(full.T_map_scan, T_map_scan_guess), config.degeneracy);
  MarkDegenerate(num_degenerate, &full.degeneracy);
  full.neighbour_searches = cache.searches;
  if (!config.degeneracy.remap || num_degenerate == 0) return full;
  // Phase 2 (Zhang et al.'s solution remapping): solve again from the guess with every update projected onto
  // the well-observed subspace, so the degenerate directions keep the guess (the prior / IMU's value).
  ScanToMapResult remapped = Solve(scan, map, T_map_scan_guess, config, num_degenerate, &cache, &problem);
  remapped.remapped = true;
  remapped.iterations += full.iterations;
  remapped.solver_iterations += full.solver_iterations;
  remapped.neighbour_searches = cache.searches;  // both phases (the cache serves both)
  return remapped;
}

}  // namespace rotolidar
