#pragma once
// Geometric verification of a loop-closure candidate (stage 2 of the two-stage loop closure of LV-SLAM, Sensors
// 2025): the two keyframes' submaps are registered from the candidate's initial guess and the loop is accepted only
// when the registration converged and the aligned submaps agree (enough overlap, small residual).
//
// Method: both submaps are voxel-downsampled (pcl::VoxelGrid, one centroid per voxel). A coarse stage runs PCL's
// Generalized-ICP (Segal, Haehnel, Thrun, "Generalized-ICP", RSS 2009) on coarser voxels with correspondences up to
// max_correspondence_m: it pulls in a guess that is off by up to ~1 m / ~10 deg. A fine stage then runs point-to-plane
// ICP (Chen & Medioni 1992) by Gauss-Newton with Huber weights on the fine voxels with fine_correspondence_m: it
// reaches the same optimum from every guess the tests tried (PCL's GICP stops on small BFGS steps and left up to
// 2 cm of error from some of them), and its Hessian at the solution gives the covariance below. Normals: PCA of the
// normal_neighbours nearest points (pcl::NormalEstimation).
//
// Gates: overlap and fitness are evaluated at fine_correspondence_m over the source's vertical structure only
// (points whose PCA normal has |z| <= structure_max_normal_z in the target frame: walls, pillars, furniture
// sides). Floors and ceilings are excluded because indoors they are most of the points and two unrelated rooms of
// the same storey share them: counted, they make any pair of rooms "overlap" (the test measures 0.79 overlap and
// 0.11 m fitness for two different halls with all points, which pass both gates; 0.33 with structure only). They
// carry no information on x, y and yaw, which is what a loop closure must fix. Precondition: the target submap's
// frame is gravity-aligned (z up), as the keyframe frames of the place descriptor and the estimator's world frame
// are.
//
// Degeneracy: a corridor or a flat field leaves a translation unconstrained; the covariance would say so only
// weakly (noisy normals: the test's featureless corridor got sigma 5 mm along its axis), so such loops are
// rejected: every translation direction must hold at least min_normal_share of the normals (the smallest
// eigenvalue of mean(n n^T) over the correspondences; measured 0.06 in a hall, < 0.001 in the corridor).
//
// Covariance: sigma^2 (J^T W J)^-1 of the point-to-plane residuals r_i = n_i . (T p_i - q_i) at the solution, over
// every source point whose nearest target point q_i (normal n_i) lies within fine_correspondence_m, with the Huber
// weights W and sigma^2 = sum w_i r_i^2 / (N - 6). Tangent convention of the project
// (core/backend/pose_factors.hpp):
//   xi = [dt (m, target frame); dtheta (rad, target frame)],  T_target_source (+) xi = (t + dt, Exp(dtheta) R),
// i.e. dr/d(dt) = n^T, dr/d(dtheta) = ((R p) x n)^T (detail::PointToPlaneResidual). It treats the points as
// independent although neighbouring voxels' errors are correlated (sampling, calibration), so it is optimistic:
// the tests print sigmas against the actual errors. The pose graph should scale it or floor it before use.
//
// Thread safety: VerifyLoop has no shared state and may run concurrently. Failure is reported in the result
// (accepted = false, reason), never thrown. Cost: about linear in the downsampled points (kd-trees, normals, the
// coarse GICP); the tests print timings.
#include <string>
#include <vector>

#include <Eigen/Core>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "core/types/geometry.hpp"

namespace rotolidar::loop {

struct LoopVerificationConfig {
  double voxel_m = 0.2;         ///< VoxelGrid leaf [m] of the fine stage and the gates (0 = no downsampling)
  double coarse_voxel_m = 0.4;  ///< leaf of the coarse stage [m] (<= voxel_m: the coarse stage uses the fine clouds)
  /// Correspondence gate of the coarse stage [m]: how far off the initial guess may be (~1 m, ~10 deg at 6 m).
  double max_correspondence_m = 1.0;
  /// Correspondence gate of the fine stage and of the overlap / fitness / covariance neighbours [m]: two voxels,
  /// so every true neighbour of a 0.2 m voxel sampling is inside, while a 1 m gate would pair unrelated walls.
  double fine_correspondence_m = 0.4;
  int max_iterations = 30;  ///< per stage (GICP iterations, Gauss-Newton steps); the fine stage must converge
  /// Fine-stage convergence: a Gauss-Newton step below both [m], [rad]. The coarse GICP stops on 10x these
  /// (changes of the transform's translation / rotation-matrix elements between iterations).
  double transformation_epsilon_m = 1e-5;
  double rotation_epsilon_rad = 1e-5;
  int normal_neighbours = 20;  ///< nearest points of each normal's PCA (fine clouds)
  /// Huber threshold of the fine stage's point-to-plane residuals [m]: ~3x the residual noise of 0.2 m voxel
  /// centroids of a VLP-16 (+-3 cm raw, averaged over a voxel), so only off-surface centroids (edges, corners,
  /// clutter) are down-weighted. Measured on the known-transform test's hall: 0.9 mm error with it, 3.9 mm without.
  double huber_m = 0.03;
  /// Degeneracy gate: every translation direction must hold at least this share of the correspondences' normals
  /// (smallest eigenvalue of mean(n n^T), at most 1/3). 0.01 lies between a hall (0.06) and a corridor (0.001).
  double min_normal_share = 0.01;
  /// A downsampled submap, and the source's vertical structure, need at least this many points.
  size_t min_points = 100;
  /// Source points whose normal has |z| (target frame) at most this count as vertical structure for the gates:
  /// 0.7 takes surfaces within ~45 deg of vertical. 1 counts every point.
  double structure_max_normal_z = 0.7;
  /// Accept only when at least this share of the source's structure points has a target point within
  /// fine_correspondence_m after alignment: half of the query's walls and objects must be seen again.
  double min_overlap = 0.5;
  /// Accept only when the RMS distance of those neighbours is at most this [m]. Two independent 0.2 m voxel
  /// samplings of the same surfaces are ~0.09 m apart (the centroids of different point subsets lie anywhere on the
  /// surface within a voxel: the test measures 0.088 m at the true alignment); a wrong place's neighbours spread
  /// over the whole 0.4 m gate (the test measures 0.24 m). 0.15 lies between, ~1.6x the correct value. It scales
  /// with voxel_m.
  double max_fitness_rmse_m = 0.15;
  bool Validate(std::string* error) const;
};

/// Outcome of VerifyLoop. Every field is filled as far as the run got, also when rejected.
struct LoopVerification {
  /// converged && enough structure && overlap >= min_overlap && fitness_rmse_m <= max_fitness_rmse_m &&
  /// normal_share >= min_normal_share && covariance_valid.
  bool accepted = false;
  bool converged = false;  ///< the fine stage's step fell below the epsilons within max_iterations
  Pose3 T_target_source = Pose3::Identity();  ///< the refined transform (the guess when registration did not run)
  double fitness_rmse_m = 0.0;  ///< RMS nearest-neighbour distance of the overlapping structure points [m]
  double overlap = 0.0;  ///< share of the source's structure points with a target point within the fine gate
  int iterations = 0;           ///< coarse GICP iterations + fine Gauss-Newton steps
  double normal_share = 0.0;    ///< the weakest translation direction's share of the normals, in [0, 1/3]
  size_t num_source_points = 0; ///< after downsampling
  size_t num_target_points = 0; ///< after downsampling
  /// Covariance of T_target_source in the tangent above: [dt (m); dtheta (rad)], units m^2, rad^2, m rad.
  /// Symmetric positive definite when covariance_valid (always when accepted); Identity otherwise.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Identity();
  bool covariance_valid = false;
  std::string reason;  ///< why it was rejected (empty when accepted)
};

/// Registers `source` onto `target` from `T_target_source_guess` and gates the result. Points are in each submap's
/// own frame [m], the target's gravity-aligned (e.g. each keyframe's gravity-aligned frame; then
/// RotZ(DescriptorMatch::yaw_rad) of the query (source) against the candidate (target) is a guess). An invalid
/// config, a non-finite guess or too few points are reported as rejected with a reason; non-finite points are
/// dropped.
LoopVerification VerifyLoop(const pcl::PointCloud<pcl::PointXYZ>& source, const pcl::PointCloud<pcl::PointXYZ>& target,
                            const Pose3& T_target_source_guess, const LoopVerificationConfig& config);
LoopVerification VerifyLoop(const std::vector<Eigen::Vector3d>& source, const std::vector<Eigen::Vector3d>& target,
                            const Pose3& T_target_source_guess, const LoopVerificationConfig& config);

namespace detail {
/// The point-to-plane residual r = n . (R p + t - q) [m] of source point p against target point q with unit normal
/// n (target frame) under T_target_source = (R, t), and (when not null) its Jacobian with respect to
/// xi = [dt; dtheta] of T (+) xi = (t + dt, Exp(dtheta) R): [n; (R p) x n]. Exposed for the tests.
double PointToPlaneResidual(const Pose3& T_target_source, const Eigen::Vector3d& p_source,
                            const Eigen::Vector3d& q_target, const Eigen::Vector3d& n_target,
                            Eigen::Matrix<double, 6, 1>* jacobian);
}  // namespace detail

}  // namespace rotolidar::loop
