#include "core/loop/geometric_verification.hpp"

#include <cmath>
#include <cstdio>

#include <Eigen/Eigenvalues>
#include <pcl/filters/voxel_grid.h>
#include <pcl/search/kdtree.h>
#include <pcl/registration/gicp.h>

#include "core/util/validation.hpp"

namespace rotolidar::loop {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// PCL's GICP keeps its iteration count and its per-point covariances protected; this exposes them. After align()
/// each covariance is U diag(1, 1, eps) U^T of the point's 20 nearest neighbours: U's last column is the normal.
class Gicp : public pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> {
 public:
  int iterations() const { return nr_iterations_; }
  const MatricesVector* source_covariances() const { return input_covariances_.get(); }
  const MatricesVector* target_covariances() const { return target_covariances_.get(); }
  MatricesVectorPtr source_covariances_ptr() const { return input_covariances_; }
  MatricesVectorPtr target_covariances_ptr() const { return target_covariances_; }
};

/// The unit normal of a GICP point covariance: the eigenvector of its smallest eigenvalue.
Eigen::Vector3d NormalOf(const Eigen::Matrix3d& covariance) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(covariance);
  return eig.eigenvectors().col(0);
}

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

Pose3 ToPose(const Eigen::Matrix4f& M) {
  const Eigen::Matrix4d D = M.cast<double>();
  return MakePose(D.block<3, 1>(0, 3), Eigen::Quaterniond(Eigen::Matrix3d(D.block<3, 3>(0, 0))));
}

/// One GICP run from `T` (updated); adds to out->iterations and ANDs the stage's convergence into out->converged.
void Align(Gicp& gicp, double gate_m, double epsilon_scale, const LoopVerificationConfig& config,
           Eigen::Matrix4f* T, LoopVerification* out) {
  gicp.setMaximumIterations(config.max_iterations);
  gicp.setMaxCorrespondenceDistance(gate_m);
  gicp.setTransformationEpsilon(epsilon_scale * config.transformation_epsilon_m);
  gicp.setRotationEpsilon(epsilon_scale * config.rotation_epsilon_rad);
  Cloud aligned;
  gicp.align(aligned, *T);
  out->iterations += gicp.iterations();
  // PCL also reports "converged" when it stops at max_iterations; that is not convergence here.
  out->converged = out->converged && gicp.hasConverged() && gicp.iterations() < config.max_iterations;
  *T = gicp.getFinalTransformation();
}

/// The coarse-to-fine schedule: the coarse stage on the coarse clouds with the wide gate and 10x looser epsilons
/// (it only has to pull the guess in), the fine stage on the fine clouds. Fills converged, iterations and
/// T_target_source; `fine` keeps the fine clouds' covariances for Evaluate.
void Register(const Cloud::Ptr& coarse_source, const Cloud::Ptr& coarse_target, const Cloud::Ptr& source,
              const Cloud::Ptr& target, const Pose3& guess, const LoopVerificationConfig& config, Gicp& fine,
              LoopVerification* out) {
  Eigen::Matrix4f T = guess.matrix().cast<float>();
  out->converged = true;
  Gicp coarse;
  coarse.setInputSource(coarse_source);
  coarse.setInputTarget(coarse_target);
  Align(coarse, config.max_correspondence_m, 10.0, config, &T, out);
  fine.setInputSource(source);
  fine.setInputTarget(target);
  if (coarse_source == source && coarse_target == target) {  // same clouds: reuse the point covariances
    fine.setSourceCovariances(coarse.source_covariances_ptr());
    fine.setTargetCovariances(coarse.target_covariances_ptr());
  }
  Align(fine, config.fine_correspondence_m, 1.0, config, &T, out);
  out->T_target_source = ToPose(T);
}

/// The nearest target point of each transformed source point within the fine gate (-1: none).
struct Correspondences {
  std::vector<int> target_index;
  std::vector<float> dist_sq_m2;
};

Correspondences FindCorrespondences(const Cloud& source, const Gicp& gicp, const Pose3& T, double gate_m) {
  Correspondences c;
  c.target_index.assign(source.size(), -1);
  c.dist_sq_m2.assign(source.size(), 0.0f);
  const auto tree = gicp.getSearchMethodTarget();
  pcl::Indices index(1);
  std::vector<float> dist_sq(1);
  for (size_t i = 0; i < source.size(); ++i) {
    const Eigen::Vector3f q = (T * source[i].getVector3fMap().cast<double>()).cast<float>();
    if (tree->nearestKSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), 1, index, dist_sq) < 1) continue;
    if (dist_sq[0] > gate_m * gate_m) continue;
    c.target_index[i] = index[0];
    c.dist_sq_m2[i] = dist_sq[0];
  }
  return c;
}

/// Overlap and fitness over the source's vertical structure (normal |z| in the target frame below the limit).
/// Returns the number of structure points.
size_t GateStatistics(const Cloud& source, const Gicp& gicp, const Correspondences& c,
                      const LoopVerificationConfig& config, LoopVerification* out) {
  const Eigen::Matrix3d R = out->T_target_source.linear();
  size_t num_structure = 0, num_inliers = 0;
  double sum_dist_sq = 0.0;
  for (size_t i = 0; i < source.size(); ++i) {
    const Eigen::Vector3d n = R * NormalOf((*gicp.source_covariances())[i]);
    if (std::abs(n.z()) > config.structure_max_normal_z) continue;
    ++num_structure;
    if (c.target_index[i] < 0) continue;
    ++num_inliers;
    sum_dist_sq += c.dist_sq_m2[i];
  }
  out->overlap = num_structure ? double(num_inliers) / double(num_structure) : 0.0;
  out->fitness_rmse_m = num_inliers ? std::sqrt(sum_dist_sq / double(num_inliers)) : 0.0;
  return num_structure;
}

/// sigma^2 (J^T J)^-1 of the point-to-plane residuals of all correspondences (floors and ceilings included: they
/// carry z, roll and pitch). False when it cannot be estimated (singular Hessian: degenerate geometry).
bool PointToPlaneCovariance(const Cloud& source, const Cloud& target, const Gicp& gicp, const Correspondences& c,
                            LoopVerification* out) {
  const Eigen::Matrix3d R = out->T_target_source.linear();
  const Eigen::Vector3d t = out->T_target_source.translation();
  Matrix6d H = Matrix6d::Zero();
  double sum_r_sq = 0.0;
  size_t n = 0;
  for (size_t i = 0; i < source.size(); ++i) {
    if (c.target_index[i] < 0) continue;
    const size_t j = size_t(c.target_index[i]);
    const Eigen::Vector3d normal = NormalOf((*gicp.target_covariances())[j]);
    const Eigen::Vector3d Rp = R * source[i].getVector3fMap().cast<double>();
    const double r = normal.dot(Rp + t - target[j].getVector3fMap().cast<double>());
    Eigen::Matrix<double, 6, 1> J;
    J << normal, Rp.cross(normal);  // d r / d[dt; dtheta] with T (+) xi = (t + dt, Exp(dtheta) R)
    H.noalias() += J * J.transpose();
    sum_r_sq += r * r;
    ++n;
  }
  if (n <= 6) return false;
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(H);
  if (eig.info() != Eigen::Success || !(eig.eigenvalues()(0) > 1e-9 * eig.eigenvalues()(5))) return false;
  const double sigma_sq = sum_r_sq / double(n - 6);
  const Matrix6d cov =
      sigma_sq * eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  out->covariance = 0.5 * (cov + cov.transpose());
  return true;
}

std::string Format(const char* format, double a, double b) {
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer), format, a, b);
  return buffer;
}

}  // namespace

bool LoopVerificationConfig::Validate(std::string* error) const {
  if (!(voxel_m >= 0.0) || !std::isfinite(voxel_m)) return FailValidation(error, "loop_verification.voxel_m must be >= 0");
  if (!(coarse_voxel_m >= 0.0) || !std::isfinite(coarse_voxel_m))
    return FailValidation(error, "loop_verification.coarse_voxel_m must be >= 0");
  if (!(fine_correspondence_m > 0.0)) return FailValidation(error, "loop_verification.fine_correspondence_m must be > 0");
  if (!(max_correspondence_m >= fine_correspondence_m) || !std::isfinite(max_correspondence_m))
    return FailValidation(error, "loop_verification.max_correspondence_m must be >= fine_correspondence_m");
  if (max_iterations < 1) return FailValidation(error, "loop_verification.max_iterations must be >= 1");
  if (!(transformation_epsilon_m > 0.0) || !(rotation_epsilon_rad > 0.0))
    return FailValidation(error, "loop_verification.transformation_epsilon_m and rotation_epsilon_rad must be > 0");
  if (!(structure_max_normal_z >= 0.0 && structure_max_normal_z <= 1.0))
    return FailValidation(error, "loop_verification.structure_max_normal_z must be in [0, 1]");
  // GICP estimates each point's covariance from its 20 nearest neighbours.
  if (min_points < 20) return FailValidation(error, "loop_verification.min_points must be >= 20");
  if (!(min_overlap >= 0.0 && min_overlap <= 1.0)) return FailValidation(error, "loop_verification.min_overlap must be in [0, 1]");
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
  const Cloud::Ptr coarse_src = coarser ? DownsampleFinite(*src, config.coarse_voxel_m) : src;
  const Cloud::Ptr coarse_tgt = coarser ? DownsampleFinite(*tgt, config.coarse_voxel_m) : tgt;
  Gicp gicp;
  Register(coarse_src, coarse_tgt, src, tgt, T_target_source_guess, config, gicp, &out);
  const auto* source_cov = gicp.source_covariances();
  const auto* target_cov = gicp.target_covariances();
  if (!source_cov || !target_cov || source_cov->size() != src->size() || target_cov->size() != tgt->size())
    return out.reason = "registration failed (no point covariances)", out;
  const Correspondences c = FindCorrespondences(*src, gicp, out.T_target_source, config.fine_correspondence_m);
  const size_t num_structure = GateStatistics(*src, gicp, c, config, &out);
  const bool covariance_ok = PointToPlaneCovariance(*src, *tgt, gicp, c, &out);
  if (!out.converged)
    out.reason = "registration did not converge within max_iterations";
  else if (num_structure < config.min_points)
    out.reason = Format("too little vertical structure to verify: %.0f points (min_points %.0f)",
                        double(num_structure), double(config.min_points));
  else if (out.overlap < config.min_overlap)
    out.reason = Format("overlap %.3f below min_overlap %.3f", out.overlap, config.min_overlap);
  else if (out.fitness_rmse_m > config.max_fitness_rmse_m)
    out.reason = Format("fitness rmse %.3f m above max_fitness_rmse_m %.3f m", out.fitness_rmse_m,
                        config.max_fitness_rmse_m);
  else if (!covariance_ok)
    out.reason = "degenerate geometry: the point-to-plane Hessian is singular";
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

}  // namespace rotolidar::loop
