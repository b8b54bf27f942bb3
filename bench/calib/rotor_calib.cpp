#include "bench/calib/rotor_calib.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include <ceres/ceres.h>
#include <Eigen/Eigenvalues>

#include "core/registration/kd_tree.hpp"
#include "core/util/validation.hpp"

namespace rotolidar::bench {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

/// PCA of the neighbours: normal (smallest eigenvector) and eigenvalues, ascending.
void FitPlane(const std::vector<float>& xyz, const int* idx, int n, Eigen::Vector3d* normal, Eigen::Vector3d* eig) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) mean += Eigen::Vector3f(&xyz[3 * idx[i]]).cast<double>();
  mean /= n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d = Eigen::Vector3f(&xyz[3 * idx[i]]).cast<double>() - mean;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov / n);
  *normal = es.eigenvectors().col(0);
  *eig = es.eigenvalues();
}

/// Builds one kd-tree per sector over its points; *members maps a tree's index back to the point.
void BuildSectorTrees(const std::vector<float>& xyz, const std::vector<int>& sector, int sectors,
                      std::vector<KdTree3f>* trees, std::vector<std::vector<int>>* members) {
  std::vector<std::vector<float>> coords(sectors);
  members->assign(sectors, {});
  for (std::size_t i = 0; i < sector.size(); ++i) {
    (*members)[sector[i]].push_back(int(i));
    coords[sector[i]].insert(coords[sector[i]].end(), &xyz[3 * i], &xyz[3 * i + 3]);
  }
  trees->assign(sectors, KdTree3f());
  for (int s = 0; s < sectors; ++s)
    if (!coords[s].empty()) (*trees)[s].Build(coords[s]);
}

/// Sets up Ceres over `associations` and solves; returns the summary.
ceres::Solver::Summary Solve(const std::vector<ResidualPoint>& table, const double* t0,
                             const std::vector<PlaneAssociation>& associations, const RotorCalibOptions& options,
                             RotorCalibParams* params) {
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  ceres::HuberLoss loss(options.huber_m);
  double* blocks[4] = {params->lever_m.data(), params->tilt_rad.data(), &params->encoder_zero_rad,
                       &params->time_offset_s};
  for (const PlaneAssociation& a : associations)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<RotorPlaneCost, 1, 3, 3, 1, 1>(
                                 new RotorPlaneCost(&table, &a, t0)),
                             &loss, blocks[0], blocks[1], blocks[2], blocks[3]);
  const int sizes[4] = {3, 3, 1, 1};
  for (int b = 0, first = 0; b < 4; first += sizes[b], ++b) {
    std::vector<int> held;
    for (int k = 0; k < sizes[b]; ++k)
      if (!options.estimate[first + k]) held.push_back(k);
    if (int(held.size()) == sizes[b]) problem.SetParameterBlockConstant(blocks[b]);
    else if (!held.empty()) problem.SetManifold(blocks[b], new ceres::SubsetManifold(sizes[b], held));
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_solver_iterations;
  so.num_threads = options.threads;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  return summary;
}

/// Largest change of a lever component [m] and of an angle [rad] between two estimates; a time offset counts as
/// the angle it turns the rotor by at `omega_radps`.
void Change(const RotorCalibParams& a, const RotorCalibParams& b, double omega_radps, double* dm, double* drad) {
  *dm = *drad = 0.0;
  for (int p = 0; p < kCalibParamCount; ++p) {
    const double d = std::abs(a.Get(p) - b.Get(p)) * (p == kTimeOffset ? omega_radps : 1.0);
    (p < kTiltX ? *dm : *drad) = std::max(p < kTiltX ? *dm : *drad, d);
  }
}

/// Mean |rotor speed| over the points [rad/s].
double MeanSpeed(const std::vector<RotorPoint>& points) {
  double sum = 0.0;
  for (const RotorPoint& p : points) sum += std::abs(p.omega_radps);
  return points.empty() ? 0.0 : sum / double(points.size());
}

}  // namespace

bool RotorCalibOptions::Validate(std::string* error) const {
  if (sectors < 2 || sectors % 2 != 0 || sectors > 64) return FailValidation(error, "sectors must be even, 2..64");
  if (max_queries < 10) return FailValidation(error, "max_queries must be >= 10");
  if (neighbours < 3 || neighbours > KdTree3f::kMaxK) return FailValidation(error, "neighbours must be 3..32");
  if (!(neighbour_radius_m > 0.0)) return FailValidation(error, "neighbour_radius_m must be > 0");
  if (!(max_plane_sigma_m > 0.0)) return FailValidation(error, "max_plane_sigma_m must be > 0");
  if (!(min_planarity >= 1.0)) return FailValidation(error, "min_planarity must be >= 1");
  if (!(huber_m > 0.0)) return FailValidation(error, "huber_m must be > 0");
  if (!(max_incidence_deg > 0.0 && max_incidence_deg <= 90.0))
    return FailValidation(error, "max_incidence_deg must be in (0, 90]");
  if (max_outer_iterations < 1 || max_solver_iterations < 1) return FailValidation(error, "iterations must be >= 1");
  if (!(tolerance_m > 0.0 && tolerance_rad > 0.0)) return FailValidation(error, "tolerances must be > 0");
  if (threads < 1) return FailValidation(error, "threads must be >= 1");
  if (std::none_of(estimate.begin(), estimate.end(), [](bool b) { return b; }))
    return FailValidation(error, "estimate: at least one parameter must be estimated");
  return true;
}

std::vector<ResidualPoint> PrepareResidualPoints(const std::vector<RotorPoint>& points, const RigCalib& calib) {
  const Eigen::Matrix3d R = calib.T_rotor_lidar.linear();
  std::vector<ResidualPoint> table(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d u = R * points[i].p_lidar.cast<double>();
    for (int k = 0; k < 3; ++k) table[i].u[k] = u[k];
    table[i].cos_theta = std::cos(points[i].theta_rad);
    table[i].sin_theta = std::sin(points[i].theta_rad);
    table[i].omega_radps = points[i].omega_radps;
  }
  return table;
}

Eigen::Vector3d RayDirectionMotor(const ResidualPoint& p) {
  const Eigen::Vector3d u(p.u[0], p.u[1], p.u[2]);
  return Eigen::Vector3d(p.cos_theta * u.x() - p.sin_theta * u.y(), p.sin_theta * u.x() + p.cos_theta * u.y(), u.z())
      .normalized();
}

void MotorFramePoints(const std::vector<ResidualPoint>& table, const double* t0, const RotorCalibParams& d,
                      std::vector<float>* xyz) {
  xyz->resize(3 * table.size());
  double out[3];
  for (std::size_t i = 0; i < table.size(); ++i) {
    MotorPoint(table[i], t0, d.lever_m.data(), d.tilt_rad.data(), d.encoder_zero_rad, d.time_offset_s, out);
    for (int k = 0; k < 3; ++k) (*xyz)[3 * i + k] = float(out[k]);
  }
}

std::vector<int> RotorSectors(const std::vector<RotorPoint>& points, const RotorCalibParams& d, int sectors) {
  std::vector<int> sector(points.size());
  const double width = 2.0 * M_PI / sectors;
  for (std::size_t i = 0; i < points.size(); ++i) {
    double a = std::fmod(points[i].theta_rad - d.encoder_zero_rad + points[i].omega_radps * d.time_offset_s,
                         2.0 * M_PI);
    if (a < 0) a += 2.0 * M_PI;
    sector[i] = std::min(sectors - 1, int(a / width));
  }
  return sector;
}

std::vector<PlaneAssociation> AssociatePlanes(const std::vector<ResidualPoint>& table, const std::vector<float>& xyz,
                                              const std::vector<int>& sector, const RotorCalibOptions& o) {
  std::vector<KdTree3f> trees;
  std::vector<std::vector<int>> members;
  BuildSectorTrees(xyz, sector, o.sectors, &trees, &members);
  const std::size_t n = sector.size(), stride = std::max<std::size_t>(1, n / std::size_t(o.max_queries));
  const float max_sq = float(o.neighbour_radius_m * o.neighbour_radius_m);
  const double min_cos = std::cos(o.max_incidence_deg * M_PI / 180.0);
  std::vector<PlaneAssociation> out;
  int idx[KdTree3f::kMaxK], global[KdTree3f::kMaxK];
  float sq[KdTree3f::kMaxK];
  for (std::size_t q = stride / 2; q < n; q += stride) {
    const int s = (sector[q] + o.sectors / 2) % o.sectors;
    if (trees[s].size() < std::size_t(o.neighbours)) continue;
    if (trees[s].Nearest(&xyz[3 * q], o.neighbours, idx, sq, max_sq) < o.neighbours) continue;
    for (int j = 0; j < o.neighbours; ++j) global[j] = members[s][idx[j]];
    Eigen::Vector3d normal, eig;
    FitPlane(xyz, global, o.neighbours, &normal, &eig);
    if (!(eig[0] <= o.max_plane_sigma_m * o.max_plane_sigma_m && eig[1] >= o.min_planarity * eig[0])) continue;
    if (std::abs(normal.dot(RayDirectionMotor(table[q]))) < min_cos) continue;
    out.push_back({int(q), std::vector<int>(global, global + o.neighbours), normal});
  }
  return out;
}

std::vector<double> PlaneResiduals(const std::vector<ResidualPoint>& table, const double* t0,
                                   const std::vector<PlaneAssociation>& associations, const RotorCalibParams& d) {
  std::vector<double> r(associations.size());
  for (std::size_t i = 0; i < associations.size(); ++i) {
    const RotorPlaneCost cost(&table, &associations[i], t0);
    cost(d.lever_m.data(), d.tilt_rad.data(), &d.encoder_zero_rad, &d.time_offset_s, &r[i]);
  }
  return r;
}

Status CalibrateRotor(const std::vector<RotorPoint>& points, const RigCalib& calib, const RotorCalibOptions& options,
                      RotorCalibResult* result) {
  std::string why;
  if (!options.Validate(&why)) return Status::Error("calibration options: " + why);
  *result = RotorCalibResult();
  const std::vector<ResidualPoint> table = PrepareResidualPoints(points, calib);
  const Eigen::Vector3d t0v = calib.T_rotor_lidar.translation();
  const double t0[3] = {t0v.x(), t0v.y(), t0v.z()};
  std::vector<float> xyz;
  std::vector<PlaneAssociation> associations;
  RotorCalibParams params;
  const double speed = MeanSpeed(points);
  for (int it = 0; it < options.max_outer_iterations && !result->converged; ++it) {
    MotorFramePoints(table, t0, params, &xyz);
    associations = AssociatePlanes(table, xyz, RotorSectors(points, params, options.sectors), options);
    if (associations.empty())
      return Status::Error("calibration: no flat neighbourhood seen from opposite rotor angles (too few points, a "
                           "rotor that turned less than half a revolution in the span, or no planes in the scene)");
    CalibIteration step;
    step.associations = int(associations.size());
    std::vector<double> r = PlaneResiduals(table, t0, associations, params);
    for (double& v : r) v = std::abs(v);
    step.median_abs_residual_m = Median(r);
    const RotorCalibParams before = params;
    const ceres::Solver::Summary summary = Solve(table, t0, associations, options, &params);
    if (!summary.IsSolutionUsable()) return Status::Error("calibration: Ceres failed: " + summary.message);
    step.initial_cost = summary.initial_cost, step.final_cost = summary.final_cost;
    step.solver_iterations = int(summary.iterations.size()) - 1;
    step.correction = params;
    result->solver_iterations += step.solver_iterations;
    result->iterations.push_back(step);
    double dm, drad;
    Change(before, params, speed, &dm, &drad);
    result->converged = it > 0 && dm <= options.tolerance_m && drad <= options.tolerance_rad;
  }
  result->correction = params;
  ComputeObservability(table, t0, associations, options, result);
  return Status::Ok();
}

}  // namespace rotolidar::bench
