#include "core/pipeline/estimator_config.hpp"

namespace rotolidar {

bool EstimatorConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (!(min_range_m >= 0 && max_range_m > min_range_m)) return fail("need 0 <= min_range_m < max_range_m");
  if (!(scan_voxel_m > 0)) return fail("scan_voxel_m must be > 0");
  if (!(cut_azimuth_deg >= 0 && cut_azimuth_deg < 360)) return fail("cut_azimuth_deg must be in [0, 360)");
  if (!(local_map_voxel_m > 0) || local_map_points_per_voxel < 1)
    return fail("local_map_voxel_m must be > 0 and local_map_points_per_voxel >= 1");
  if (!(local_map_radius_m > max_range_m * 0.25)) return fail("local_map_radius_m must exceed max_range_m / 4");
  if (target_refresh_scans < 1) return fail("target_refresh_scans must be >= 1");
  if (!(output_map_voxel_m > 0) || output_map_points_per_voxel < 1)
    return fail("output_map_voxel_m must be > 0 and output_map_points_per_voxel >= 1");
  return registration.Validate(error);
}

}  // namespace rotolidar
