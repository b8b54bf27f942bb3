#pragma once
// Runs the core estimator over a recording folder and writes its outputs:
//   trajectory.tum, trajectory.kitti (+ trajectory_times.txt)   T_world_base at each scan start
//   map.ply, map.pcd                                            the dense map [world, m]
//   scans.csv          per scan: stage timings [ms], feature counts, registration, degeneracy (eigenvalues, axes)
//   slam_config.yaml                                            the resolved estimator config
#include <functional>
#include <string>
#include <vector>

#include "core/pipeline/estimator.hpp"
#include "core/types/trajectory.hpp"
#include "core/util/log.hpp"

namespace rotolidar::bench {

struct SlamRunResult {
  Trajectory trajectory;            ///< T_world_base
  std::vector<ScanReport> scans;
  size_t map_points = 0;
  size_t bad_packets = 0;
  double data_duration_s = 0.0;     ///< span of the LiDAR data [s]
  double wall_time_s = 0.0;         ///< estimator time only (excludes loading) [s]
  double median_scan_ms = 0.0;      ///< median Process time per scan [ms]
};

/// `progress(fraction)` is called about every 10 % of the data.
Status RunSlam(const std::string& recording_dir, const EstimatorConfig& config, const std::string& out_dir,
               SlamRunResult* result, const std::function<void(double)>& progress = nullptr);

}  // namespace rotolidar::bench
