#pragma once
// Configuration of the estimator (plain structs, defaults in-class, units in comments).
// YAML I/O lives at the edge: core/io/config_yaml.hpp.
#include <string>

#include "core/pipeline/scan_matcher.hpp"

namespace rotolidar {

struct EstimatorConfig {
  // Preprocessing
  double min_range_m = 0.8;          ///< drop returns closer than this (rig body, operator) [m]
  double max_range_m = 60.0;         ///< drop returns farther than this [m]
  double scan_voxel_m = 0.15;        ///< registration source downsampling [m]
  double cut_azimuth_deg = 0.0;      ///< VLP-16 head azimuth where one revolution ends and the next begins [deg]
  // Local map (registration target)
  double local_map_voxel_m = 0.2;    ///< [m]
  int local_map_points_per_voxel = 8;
  double local_map_radius_m = 40.0;  ///< voxels farther than this from the rig are dropped [m]
  int target_refresh_scans = 5;      ///< rebuild the registration target at least every N scans
  // Dense output map
  double output_map_voxel_m = 0.05;  ///< [m]
  int output_map_points_per_voxel = 1;
  // Registration
  ScanMatcherConfig registration;

  bool Validate(std::string* error) const;
};

}  // namespace rotolidar
