#include "core/pipeline/estimator_config.hpp"

#include <cmath>

namespace rotolidar {

FeatureConfig EstimatorFeatureDefaults() {
  FeatureConfig c;
  c.planars_per_sector = 20;
  c.planar_voxel_m = 0.25;
  c.less_flat_voxel_m = 0.3;
  c.edge_min_snr = 5.0;
  c.range_sigma_m = kRangeSigmaFromCalib;
  return c;
}

LocalMapConfig EstimatorLocalMapDefaults() {
  LocalMapConfig c;
  c.planar_voxel_m = 0.2;
  c.max_keyframes = 40;
  return c;
}

ScanToMapConfig EstimatorRegistrationDefaults() {
  ScanToMapConfig c;
  c.neighbour_reuse_m = 0.05;
  return c;
}

SlidingWindowConfig EstimatorWindowDefaults() {
  SlidingWindowConfig c;
  c.max_iterations = 3;
  c.linear_solver = ceres::SPARSE_NORMAL_CHOLESKY;
  return c;
}

bool EstimatorConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (!(cut_azimuth_deg >= 0 && cut_azimuth_deg < 360)) return fail("cut_azimuth_deg must be in [0, 360)");
  FeatureConfig features_resolved = features;  // kRangeSigmaFromCalib is resolved by the Estimator
  if (features_resolved.range_sigma_m == kRangeSigmaFromCalib) features_resolved.range_sigma_m = 0.0;
  if (!preprocess.Validate(error) || !features_resolved.Validate(error) || !registration.Validate(error) ||
      !local_map.Validate(error) || !window.Validate(error) || !imu_init.Validate(error))
    return false;
  if (!(lidar_point_sigma_m > 0) || !std::isfinite(lidar_point_sigma_m))
    return fail("lidar_point_sigma_m must be > 0");
  if (keyframe_every_scans < 1) return fail("keyframe_every_scans must be >= 1");
  if (initial_keyframes < 0) return fail("initial_keyframes must be >= 0");
  if (imu_init_scans < 3) return fail("imu_init_scans must be >= 3");
  if (imu_init_scans < imu_init.moving_min_poses)
    return fail("imu_init_scans must be >= imu_init.moving_min_poses");
  if (!(unconverged_information_scale >= 0 && unconverged_information_scale <= 1))
    return fail("unconverged_information_scale must be in [0, 1]");
  if (!(output_map_voxel_m > 0) || output_map_points_per_voxel < 1)
    return fail("output_map_voxel_m must be > 0 and output_map_points_per_voxel >= 1");
  if (!(output_map_max_range_m > 0)) return fail("output_map_max_range_m must be > 0");
  return true;
}

}  // namespace rotolidar
