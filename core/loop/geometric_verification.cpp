#include "core/loop/geometric_verification.hpp"

#include <cmath>
#include <cstdio>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/registration/gicp.h>
#include <pcl/search/kdtree.h>

#include "core/util/validation.hpp"

namespace rotolidar::loop {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using KdTree = pcl::search::KdTree<pcl::PointXYZ>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

/// PCL's GICP keeps its iteration count protected; this exposes it.
class Gicp : public pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> {
 public:
  int iterations() const { return nr_iterations_; }
};

/// The finite points of `in`, voxel-downsampled when voxel_m > 0.
Cloud::Ptr DownsampleFinite(const Cloud& in, double voxel_m) {
  Cloud::Ptr finite(new Cloud);
  finite->reserve(in.size());
  for (const auto& p : in)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) finite->push_back(p);
  if (voxel_m <= 0.0 || finite->empty()) return finite;
  Cloud::Ptr out(new Cloud);
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setLeafSize(float(voxel_m), float(voxel_m), float(voxel_m));
  grid.setInputCloud(finite);
  grid.filter(*out);
  return out;
}

/// Coarse stage: GICP with the wide gate and 10x looser epsilons (it only has to pull the guess in). Returns its
/// transform (the guess when it failed outright or a coarse cloud is too small); the fine stage and the gates judge
/// the result.
Pose3 CoarseAlign(const Cloud::Ptr& source, const Cloud::Ptr& target, const Pose3& guess,
                  const LoopVerificationConfig& config, int* iterations) {
  Gicp gicp;
  // PCL's GICP needs k_correspondences (20) neighbours per point and indexes missing covariances otherwise.
  if (source->size() < size_t(gicp.getCorrespondenceRandomness()) ||
      target->size() < size_t(gicp.getCorrespondenceRandomness()))
    return guess;
  gicp.setInputSource(source);
  gicp.setInputTarget(target);
  gicp.setMaximumIterations(config.max_iterations);
  gicp.setMaxCorrespondenceDistance(config.max_correspondence_m);
  gicp.setTransformationEpsilon(10.0 * config.transformation_epsilon_m);
  gicp.setRotationEpsilon(10.0 * config.rotation_epsilon_rad);
  Cloud aligned;
  gicp.align(aligned, guess.matrix().cast<float>());
  *iterations += gicp.iterations();
  const Eigen::Matrix4d M = gicp.getFinalTransformation().cast<double>();
  if (!M.allFinite()) return guess;
  return MakePose(M.block<3, 1>(0, 3), Eigen::Quaterniond(Eigen::Matrix3d(M.block<3, 3>(0, 0))));
}

/// A fine cloud with its kd-tree and unit normals (zero where PCA found none).
struct FineCloud {
  Cloud::Ptr points;
  KdTree::Ptr tree;
  std::vector<Eigen::Vector3d> normals;
};

FineCloud MakeFineCloud(const Cloud::Ptr& points, int normal_neighbours) {
  FineCloud f{points, KdTree::Ptr(new KdTree), {}};
  f.tree->setInputCloud(points);
  pcl::PointCloud<pcl::Normal> normals;
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimation;
  estimation.setInputCloud(points);
  estimation.setSearchMethod(f.tree);
  estimation.setKSearch(normal_neighbours);
  estimation.compute(normals);
  f.normals.reserve(normals.size());
  for (const auto& n : normals) {
    const Eigen::Vector3d v(n.normal_x, n.normal_y, n.normal_z);
    f.normals.push_back(v.allFinite() && v.norm() > 0.5 ? v.normalized() : Eigen::Vector3d::Zero());
  }
  return f;
}

/// Huber-weighted point-to-plane normal equations at T over the source points whose nearest target point lies
/// within the gate.
struct PlaneSystem {
  Matrix6d H = Matrix6d::Zero();  ///< J^T J
  Vector6d g = Vector6d::Zero();  ///< J^T r
  double sum_r_sq = 0.0;           ///< sum of w r^2
  size_t num_residuals = 0;
  std::vector<int> target_index;   ///< per source point: its target neighbour within the gate, or -1
  std::vector<float> dist_sq_m2;   ///< per source point: squared distance to that neighbour
};

PlaneSystem BuildSystem(const FineCloud& source, const FineCloud& target, const Pose3& T, double gate_m,
                        double huber_m) {
  PlaneSystem s;
  s.target_index.assign(source.points->size(), -1);
  s.dist_sq_m2.assign(source.points->size(), 0.0f);
  pcl::Indices index(1);
  std::vector<float> dist_sq(1);
  for (size_t i = 0; i < source.points->size(); ++i) {
    const Eigen::Vector3d p = (*source.points)[i].getVector3fMap().cast<double>();
    const Eigen::Vector3f q = (T * p).cast<float>();
    if (target.tree->nearestKSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), 1, index, dist_sq) < 1) continue;
    if (dist_sq[0] > gate_m * gate_m) continue;
    s.target_index[i] = index[0];
    s.dist_sq_m2[i] = dist_sq[0];
    const Eigen::Vector3d& n = target.normals[size_t(index[0])];
    if (n.isZero()) continue;
    Vector6d J;
    const double r = detail::PointToPlaneResidual(
        T, p, (*target.points)[size_t(index[0])].getVector3fMap().cast<double>(), n, &J);
    // Huber IRLS weight: voxel centroids at edges and corners sit off the surfaces and, unweighted, biased the
    // solution by ~5 mm in the tests.
    const double w = std::abs(r) <= huber_m ? 1.0 : huber_m / std::abs(r);
    s.H.noalias() += w * J * J.transpose();
    s.g += w * J * r;
    s.sum_r_sq += w * r * r;
    ++s.num_residuals;
  }
  return s;
}

/// Fine stage: Gauss-Newton on the point-to-plane residuals, T (+) xi = (t + dt, Exp(dtheta) R). True when a step
/// fell below the epsilons within max_iterations.
bool RefinePointToPlane(const FineCloud& source, const FineCloud& target, const LoopVerificationConfig& config,
                        Pose3* T, int* iterations) {
  for (int it = 0; it < config.max_iterations; ++it) {
    const PlaneSystem s = BuildSystem(source, target, *T, config.fine_correspondence_m, config.huber_m);
    if (s.num_residuals < 6) return false;
    const Eigen::LDLT<Matrix6d> ldlt(s.H);
    const Vector6d xi = -ldlt.solve(s.g);
    if (ldlt.info() != Eigen::Success || !xi.allFinite()) return false;
    T->translation() += xi.head<3>();
    T->linear() = ExpSO3(xi.tail<3>()) * T->linear();
    ++*iterations;
    if (xi.head<3>().norm() < config.transformation_epsilon_m && xi.tail<3>().norm() < config.rotation_epsilon_rad)
      return true;
  }
  return false;
}

/// Gates and covariance at out->T_target_source from the final system. Returns the number of structure points.
size_t Evaluate(const FineCloud& source, const PlaneSystem& s, const LoopVerificationConfig& config,
                LoopVerification* out) {
  const Eigen::Matrix3d R = out->T_target_source.linear();
  size_t num_structure = 0, num_inliers = 0;
  double sum_dist_sq = 0.0;
  for (size_t i = 0; i < source.points->size(); ++i) {
    const Eigen::Vector3d& n = source.normals[i];
    if (n.isZero() || std::abs((R * n).z()) > config.structure_max_normal_z) continue;
    ++num_structure;
    if (s.target_index[i] < 0) continue;
    ++num_inliers;
    sum_dist_sq += s.dist_sq_m2[i];
  }
  out->overlap = num_structure ? double(num_inliers) / double(num_structure) : 0.0;
  out->fitness_rmse_m = num_inliers ? std::sqrt(sum_dist_sq / double(num_inliers)) : 0.0;
  if (s.num_residuals <= 6) return num_structure;
  // The weakest translation direction's share of the normals: the smallest eigenvalue of mean(n n^T).
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> shares(s.H.topLeftCorner<3, 3>() / double(s.num_residuals));
  out->normal_share = shares.eigenvalues()(0);
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(s.H);
  if (eig.info() != Eigen::Success || !(eig.eigenvalues()(0) > 1e-12 * eig.eigenvalues()(5))) return num_structure;
  const double sigma_sq = s.sum_r_sq / double(s.num_residuals - 6);
  const Matrix6d cov =
      sigma_sq * eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  out->covariance = 0.5 * (cov + cov.transpose());
  out->covariance_valid = true;
  return num_structure;
}

std::string Format(const char* format, double a, double b) {
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer), format, a, b);
  return buffer;
}

/// The first failed gate, or "" when all pass: overlap and fitness first, as they say most about a wrong place.
std::string RejectionReason(const LoopVerification& out, size_t num_structure, const LoopVerificationConfig& config) {
  if (num_structure < config.min_points)
    return Format("too little vertical structure to verify: %.0f points (min_points %.0f)", double(num_structure),
                  double(config.min_points));
  if (out.overlap < config.min_overlap)
    return Format("overlap %.3f below min_overlap %.3f", out.overlap, config.min_overlap);
  if (out.fitness_rmse_m > config.max_fitness_rmse_m)
    return Format("fitness rmse %.3f m above max_fitness_rmse_m %.3f m", out.fitness_rmse_m,
                  config.max_fitness_rmse_m);
  if (out.normal_share < config.min_normal_share)
    return Format("degenerate geometry: the weakest direction holds %.4f of the normals (min_normal_share %.4f)",
                  out.normal_share, config.min_normal_share);
  if (!out.converged) return "point-to-plane refinement did not converge within max_iterations";
  if (!out.covariance_valid) return "degenerate geometry: the point-to-plane Hessian is singular";
  return "";
}

}  // namespace

bool LoopVerificationConfig::Validate(std::string* error) const {
  if (!(voxel_m >= 0.0) || !std::isfinite(voxel_m))
    return FailValidation(error, "loop_verification.voxel_m must be >= 0");
  if (!(coarse_voxel_m >= 0.0) || !std::isfinite(coarse_voxel_m))
    return FailValidation(error, "loop_verification.coarse_voxel_m must be >= 0");
  if (!(fine_correspondence_m > 0.0))
    return FailValidation(error, "loop_verification.fine_correspondence_m must be > 0");
  if (!(max_correspondence_m >= fine_correspondence_m) || !std::isfinite(max_correspondence_m))
    return FailValidation(error, "loop_verification.max_correspondence_m must be >= fine_correspondence_m");
  if (max_iterations < 1) return FailValidation(error, "loop_verification.max_iterations must be >= 1");
  if (!(transformation_epsilon_m > 0.0) || !(rotation_epsilon_rad > 0.0))
    return FailValidation(error, "loop_verification.transformation_epsilon_m and rotation_epsilon_rad must be > 0");
  if (!(huber_m > 0.0)) return FailValidation(error, "loop_verification.huber_m must be > 0");
  if (normal_neighbours < 3) return FailValidation(error, "loop_verification.normal_neighbours must be >= 3");
  if (!(min_normal_share >= 0.0 && min_normal_share <= 1.0 / 3.0))
    return FailValidation(error, "loop_verification.min_normal_share must be in [0, 1/3]");
  if (!(structure_max_normal_z >= 0.0 && structure_max_normal_z <= 1.0))
    return FailValidation(error, "loop_verification.structure_max_normal_z must be in [0, 1]");
  if (min_points < 20) return FailValidation(error, "loop_verification.min_points must be >= 20");
  if (!(min_overlap >= 0.0 && min_overlap <= 1.0))
    return FailValidation(error, "loop_verification.min_overlap must be in [0, 1]");
  if (!(max_fitness_rmse_m > 0.0)) return FailValidation(error, "loop_verification.max_fitness_rmse_m must be > 0");
  return true;
}

LoopVerification VerifyLoop(const Cloud& source, const Cloud& target, const Pose3& T_target_source_guess,
                            const LoopVerificationConfig& config) {
  LoopVerification out;
  out.T_target_source = T_target_source_guess;
  std::string error;
  if (!config.Validate(&error)) return out.reason = "invalid config: " + error, out;
  if (!T_target_source_guess.matrix().allFinite()) return out.reason = "initial guess is not finite", out;
  const Cloud::Ptr src = DownsampleFinite(source, config.voxel_m);
  const Cloud::Ptr tgt = DownsampleFinite(target, config.voxel_m);
  out.num_source_points = src->size();
  out.num_target_points = tgt->size();
  if (src->size() < config.min_points || tgt->size() < config.min_points)
    return out.reason = Format("too few points after downsampling: source %.0f, target %.0f", double(src->size()),
                               double(tgt->size())),
           out;
  const bool coarser = config.coarse_voxel_m > config.voxel_m;
  const Pose3 coarse = CoarseAlign(coarser ? DownsampleFinite(*src, config.coarse_voxel_m) : src,
                                   coarser ? DownsampleFinite(*tgt, config.coarse_voxel_m) : tgt,
                                   T_target_source_guess, config, &out.iterations);
  const FineCloud fine_src = MakeFineCloud(src, config.normal_neighbours);
  const FineCloud fine_tgt = MakeFineCloud(tgt, config.normal_neighbours);
  out.T_target_source = coarse;
  out.converged = RefinePointToPlane(fine_src, fine_tgt, config, &out.T_target_source, &out.iterations);
  const PlaneSystem final_system = BuildSystem(fine_src, fine_tgt, out.T_target_source,
                                                 config.fine_correspondence_m, config.huber_m);
  const size_t num_structure = Evaluate(fine_src, final_system, config, &out);
  out.reason = RejectionReason(out, num_structure, config);
  out.accepted = out.reason.empty();
  return out;
}

LoopVerification VerifyLoop(const std::vector<Eigen::Vector3d>& source, const std::vector<Eigen::Vector3d>& target,
                            const Pose3& T_target_source_guess, const LoopVerificationConfig& config) {
  Cloud src, tgt;
  src.reserve(source.size());
  tgt.reserve(target.size());
  for (const auto& p : source) src.push_back(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())));
  for (const auto& p : target) tgt.push_back(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())));
  return VerifyLoop(src, tgt, T_target_source_guess, config);
}

namespace detail {

double PointToPlaneResidual(const Pose3& T_target_source, const Eigen::Vector3d& p_source,
                            const Eigen::Vector3d& q_target, const Eigen::Vector3d& n_target,
                            Eigen::Matrix<double, 6, 1>* jacobian) {
  const Eigen::Vector3d Rp = T_target_source.linear() * p_source;
  if (jacobian) *jacobian << n_target, Rp.cross(n_target);  // d/d(dt) = n; d/d(dtheta): n . (dtheta x Rp)
  return n_target.dot(Rp + T_target_source.translation() - q_target);
}

}  // namespace detail
}  // namespace rotolidar::loop
