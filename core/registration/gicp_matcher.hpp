#pragma once
// Pairwise registration of two point clouds with PCL's Generalized-ICP (plane-to-plane). The estimator's odometry
// registers with the seed's feature-based Ceres scan-to-map (scan_to_map.hpp); this dense GICP is the independent
// reference for tests and real-data checks. PCL stays inside the .cpp.
#include <memory>
#include <vector>

#include "core/types/geometry.hpp"

namespace rotolidar {

struct GicpConfig {
  double max_correspondence_m = 0.5;   ///< correspondences farther than this are rejected [m]
  int max_iterations = 30;
  double transformation_epsilon = 1e-6;  ///< convergence: squared change of the transform between iterations
  int k_correspondences = 10;            ///< neighbours for each point's covariance
  bool Validate(std::string* error) const;
};

/// Outcome of one registration. T_target_source maps source points into the target frame.
struct RegistrationResult {
  bool converged = false;
  int iterations = 0;
  size_t num_inliers = 0;      ///< source points within max_correspondence_m of the target after alignment
  double rmse_m = 0.0;         ///< RMS distance of the inliers to their nearest target point [m]
  Pose3 T_target_source = Pose3::Identity();
};

/// Holds a target cloud (with its kd-tree and covariances) and aligns source clouds to it.
/// Not thread-safe: one matcher per thread.
class GicpMatcher {
 public:
  explicit GicpMatcher(const GicpConfig& config);
  ~GicpMatcher();
  GicpMatcher(const GicpMatcher&) = delete;
  GicpMatcher& operator=(const GicpMatcher&) = delete;

  /// Replaces the target (points in the target frame, e.g. world). Cost grows with its size (kd-tree + covariances).
  void SetTarget(const std::vector<Eigen::Vector3d>& p_target);
  /// Aligns `p_source` starting from `T_target_source_guess`. Fails (converged = false) without a target.
  RegistrationResult Align(const std::vector<Eigen::Vector3d>& p_source, const Pose3& T_target_source_guess);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// PCL VoxelGrid downsampling (one centroid per occupied voxel of `voxel_size_m`).
std::vector<Eigen::Vector3d> VoxelDownsample(const std::vector<Eigen::Vector3d>& points, double voxel_size_m);

}  // namespace rotolidar
