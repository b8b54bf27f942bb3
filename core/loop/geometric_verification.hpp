#pragma once
// Geometric verification of a loop-closure candidate (stage 2 of the two-stage loop closure of LV-SLAM, Sensors
// 2025): the two keyframes' submaps are registered from the candidate's initial guess and the loop is accepted only
// when the registration converged and the aligned submaps agree (enough overlap, small residual).
//
// Method: both submaps are voxel-downsampled (pcl::VoxelGrid, one centroid per voxel), then aligned by PCL's
// Generalized-ICP (Segal, Haehnel, Thrun, "Generalized-ICP", RSS 2009) in a coarse-to-fine schedule: a coarse stage
// on coarser voxels with correspondences up to max_correspondence_m pulls in a guess that is off by up to ~1 m /
// ~10 deg, a fine stage with fine_correspondence_m refines on true neighbours only.
//
// Gates: overlap and fitness are evaluated at fine_correspondence_m over the source's vertical structure only
// (points whose GICP normal has |z| <= structure_max_normal_z in the target frame: walls, pillars, furniture
// sides). Floors and ceilings are excluded because indoors they are most of the points and two unrelated rooms of
// the same storey share them: counted, they make any pair of rooms "overlap" (the test measures 0.83 overlap for
// two different halls with all points, 0.32 with structure only). They carry no information on x, y and yaw, which
// is what a loop closure must fix. Precondition: both submap frames are gravity-aligned (z up), as the keyframe
// frames of the place descriptor and the estimator's world frame are.
//
// Covariance: point-to-plane Gauss-Newton at the solution, sigma^2 (J^T J)^-1, with r_i = n_i . (T p_i - q_i) for
// every source point whose nearest target point q_i (normal n_i: the smallest-eigenvalue direction of GICP's
// neighbourhood covariance of q_i) lies within fine_correspondence_m, and sigma^2 = sum r_i^2 / (N - 6). Tangent
// convention of the project (core/backend/pose_factors.hpp):
//   xi = [dt (m, target frame); dtheta (rad, target frame)],  T_target_source (+) xi = (t + dt, Exp(dtheta) R),
// i.e. dr/d(dt) = n^T, dr/d(dtheta) = ((R p) x n)^T. It treats the points as independent although neighbouring
// voxels' errors are correlated (sampling, calibration), so it is optimistic: the test measures sigmas of
// ~0.5 mm / 0.002 deg against errors of a few mm. The pose graph should scale it or floor it before use.
//
// Thread safety: VerifyLoop has no shared state and may run concurrently. Failure is reported in the result
// (accepted = false, reason), never thrown. Cost: dominated by GICP, about linear in the downsampled points
// (the tests print timings: ~1 s for two 50 k-point submaps on one loaded core).
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
  int max_iterations = 50;  ///< GICP iterations per stage; stopping there counts as not converged
  /// Fine-stage convergence: the change between iterations of every translation element [m] and rotation-matrix
  /// element [rad]; the coarse stage uses 10x these. GICP takes small steps, so a loose epsilon stops it early:
  /// 1e-4 left 13 mm of error in the test, 1e-6 leaves ~2 mm.
  double transformation_epsilon_m = 1e-6;
  double rotation_epsilon_rad = 1e-6;
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
  /// converged && enough structure && overlap >= min_overlap && fitness_rmse_m <= max_fitness_rmse_m && the
  /// covariance could be estimated (a singular point-to-plane Hessian means degenerate geometry).
  bool accepted = false;
  bool converged = false;  ///< both GICP stages stopped on the epsilons (not on max_iterations or an error)
  Pose3 T_target_source = Pose3::Identity();  ///< the refined transform (the guess when registration did not run)
  double fitness_rmse_m = 0.0;  ///< RMS nearest-neighbour distance of the overlapping structure points [m]
  double overlap = 0.0;  ///< share of the source's structure points with a target point within the fine gate
  int iterations = 0;           ///< GICP iterations, both stages
  size_t num_source_points = 0; ///< after downsampling
  size_t num_target_points = 0; ///< after downsampling
  /// Covariance of T_target_source in the tangent above: [dt (m); dtheta (rad)], units m^2, rad^2, m rad.
  /// Symmetric positive definite when accepted; Identity when it could not be estimated.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Identity();
  std::string reason;  ///< why it was rejected (empty when accepted)
};

/// Registers `source` onto `target` from `T_target_source_guess` and gates the result. Points are in each submap's
/// own gravity-aligned frame [m] (e.g. each keyframe's; then RotZ(DescriptorMatch::yaw_rad) of the query (source)
/// against the candidate (target) is a guess). An invalid config, a non-finite guess or too few points are reported
/// as rejected with a reason; non-finite points are dropped.
LoopVerification VerifyLoop(const pcl::PointCloud<pcl::PointXYZ>& source, const pcl::PointCloud<pcl::PointXYZ>& target,
                            const Pose3& T_target_source_guess, const LoopVerificationConfig& config);
LoopVerification VerifyLoop(const std::vector<Eigen::Vector3d>& source, const std::vector<Eigen::Vector3d>& target,
                            const Pose3& T_target_source_guess, const LoopVerificationConfig& config);

}  // namespace rotolidar::loop
