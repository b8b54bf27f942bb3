#include "core/pipeline/estimator_config.hpp"

#include <algorithm>
#include <cmath>

namespace rotolidar {

KeyframePolicy RotaryKeyframePolicy(const RigCalib& calib, const LocalMapConfig& local_map) {
  const double per_scan_rad = std::abs(calib.motor_speed_radps) * 60.0 / calib.lidar.rpm;
  KeyframePolicy p;
  if (!(per_scan_rad >= 1e-6)) return {0, 0};
  constexpr double kFanRad = 30.0 * M_PI / 180.0;  // VLP-16 elevations -15..+15 deg
  p.every_scans = std::max(1, int(std::floor(kFanRad / per_scan_rad)));
  p.initial_keyframes = int(std::min<double>(std::floor(2.0 * M_PI / per_scan_rad), local_map.max_keyframes));
  return p;
}

EstimatorConfig ResolveFromCalib(const EstimatorConfig& config, const RigCalib& calib) {
  EstimatorConfig c = config;
  if (c.features.range_sigma_m == kRangeSigmaFromCalib) c.features.range_sigma_m = calib.lidar.range_sigma_m;
  const KeyframePolicy policy = RotaryKeyframePolicy(calib, c.local_map);
  if (c.keyframe_every_scans == kDeriveFromCalib) c.keyframe_every_scans = policy.every_scans;
  if (c.initial_keyframes == kDeriveFromCalib) c.initial_keyframes = policy.initial_keyframes;
  if (c.visual.enabled) c.registration.degeneracy.weak_gate_m = c.visual.registration_weak_gate_m;
  else if (!c.use_imu) c.registration.degeneracy.weak_gate_m = c.lidar_only_weak_gate_m;
  if (!c.use_imu) c.registration.max_correspondence_rebuilds = c.lidar_only_max_correspondence_rebuilds;
  return c;
}

bool EstimatorConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (!(cut_azimuth_deg >= 0 && cut_azimuth_deg < 360)) return fail("cut_azimuth_deg must be in [0, 360)");
  if (std::string why; !packet_order.Validate(&why)) return fail("packet_order." + why);
  FeatureConfig features_resolved = features;  // kRangeSigmaFromCalib is resolved by the Estimator
  if (features_resolved.range_sigma_m == kRangeSigmaFromCalib) features_resolved.range_sigma_m = 0.0;
  if (!preprocess.Validate(error) || !features_resolved.Validate(error) || !registration.Validate(error) ||
      !local_map.Validate(error) || !window.Validate(error) || !imu_init.Validate(error) ||
      !free_space.Validate(error) || !loop_closure.Validate(error) || !visual.Validate(error))
    return false;
  if (!(lidar_point_sigma_m > 0) || !std::isfinite(lidar_point_sigma_m))
    return fail("lidar_point_sigma_m must be > 0");
  if (!(lidar_only_weak_gate_m > 0) || !std::isfinite(lidar_only_weak_gate_m))
    return fail("lidar_only_weak_gate_m must be finite and > 0");
  if (!(lidar_only_velocity_window_s >= 0) || !std::isfinite(lidar_only_velocity_window_s))
    return fail("lidar_only_velocity_window_s must be finite and >= 0");
  if (lidar_only_max_correspondence_rebuilds < 1) return fail("lidar_only_max_correspondence_rebuilds must be >= 1");
  if (keyframe_every_scans < 0 && keyframe_every_scans != kDeriveFromCalib)
    return fail("keyframe_every_scans must be >= 0 (or -1: derived from calib)");
  if (initial_keyframes < 0 && initial_keyframes != kDeriveFromCalib)
    return fail("initial_keyframes must be >= 0 (or -1: derived from calib)");
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
