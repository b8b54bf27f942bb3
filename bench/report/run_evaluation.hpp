#pragma once
// Everything a run report shows beyond the SLAM outputs themselves, gathered once per run: the trajectory
// errors against the sim's truth (<recording>/truth/base.tum: APE after SE(3) Umeyama, RPE over 1 m of path)
// and the map metrics against the scene (bench/metrics/map_metrics.hpp), with the map moved into the scene
// frame by the same SE(3) alignment as the APE, and the per-point deskew error (bench/metrics/deskew_error.hpp)
// when the run kept its deskewed points (EstimatorConfig::keep_deskewed; `rotolidar demo` does). A real-rig
// recording has no truth/: the truth parts stay empty and `truth_note` / `map_note` / `deskew_note` say why
// (the report leaves their sections out), never faked.
//
// Only bench/ reads truth; the core never sees it. Not thread-safe per result; no randomness.
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "bench/metrics/deskew_error.hpp"
#include "bench/metrics/dynamic_share.hpp"
#include "bench/metrics/map_metrics.hpp"
#include "bench/run/eval_run.hpp"
#include "bench/run/slam_run.hpp"
#include "core/types/trajectory.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

struct RunEvaluationOptions {
  bool map_metrics = true;       ///< compute map metrics when truth and the scene are available
  bool completeness = true;      ///< visibility from the true base positions (Embree rays; costs time)
  MapMetricsConfig map;          ///< viewpoints are filled from the truth when `completeness`
  /// The dynamic-object share (dynamic_share.hpp), computed whenever the truth has dynamic_hits.csv and the
  /// scene loads; set voxel_m to the run's dense-map voxel (EstimatorConfig::output_map_voxel_m).
  DynamicShareConfig dynamic;
  double rpe_delta_m = 1.0;      ///< RPE pair distance along the path [m]
  int rpe_fallback_frames = 10;  ///< used instead when the path is too short for one metric pair

  bool Validate(std::string* error) const;
};

struct RunEvaluation {
  // Map (always, when <slam>/map.ply reads): in the scene frame when has_truth, else the SLAM world.
  std::vector<Eigen::Vector3f> map_points;
  bool map_in_scene_frame = false;
  std::string map_note;  ///< why the map or its metrics are missing; empty when present

  // Truth (has_truth = <recording>/truth/base.tum was read and the APE succeeded).
  bool has_truth = false;
  std::string truth_note;       ///< why there is no truth comparison; empty when has_truth
  EvalResult ape;               ///< translation APE [m], SE(3) Umeyama (truth_eval.hpp)
  EvalResult rpe;               ///< translation RPE [m] per pair, already associated (no alignment needed)
  std::string rpe_delta;        ///< "1 m" or "10 frames"
  Trajectory truth;             ///< T_scene_base interpolated at the estimate's stamps
  Trajectory estimate_aligned;  ///< the estimate mapped into the scene frame by the APE alignment
  Eigen::Isometry3d T_scene_slam = Eigen::Isometry3d::Identity();  ///< = ape.alignment.T_ref_est
  /// Places map.ply in the scene: T_scene_slam, except after loop closure, where map.ply is the odometry's dense
  /// map while the trajectory is corrected: then the odometry trajectory's own SE(3) alignment.
  Eigen::Isometry3d T_scene_map = Eigen::Isometry3d::Identity();

  // Deskew error (has_deskew = truth, truth/lidar.tum, the run kept deskew data and >= 1 point was scored):
  // over the scans that kept their points, every deskew_scan_stride-th one (SlamRunResult::deskew_scan_stride).
  bool has_deskew = false;
  std::string deskew_note;  ///< why there is no deskew error; empty when has_deskew
  DeskewErrorResult deskew;
  size_t deskew_scan_stride = 0;

  // Map metrics (has_map_metrics = truth, a loadable scene and ComputeMapMetrics succeeded).
  bool has_map_metrics = false;
  std::string scene_name;
  MapMetrics map;  ///< per-point distances follow map_points' order
  MapMetricsConfig map_config;  ///< the config the metrics were computed with (viewpoints included)
  double map_metrics_wall_s = 0.0;

  // Dynamic-object share (has_dynamic = truth, <recording>/truth/dynamic_hits.csv, a non-empty map and, when
  // there are hits, a loadable scene): how many points of the walkers and cars reached the dense map.
  bool has_dynamic = false;
  std::string dynamic_note;  ///< why there is no dynamic share; empty when has_dynamic
  DynamicShare dynamic;
  DynamicShareConfig dynamic_config;  ///< the thresholds used
};

/// Evaluates a finished run. Reads <slam_dir>/map.ply; with <recording_dir>/truth/base.tum computes APE / RPE;
/// with truth, truth/lidar.tum and slam.deskew_scan_stride > 0 the deskew error; with truth and a scene
/// (`scene_name_or_path`, or when empty the scene of <recording_dir>/sim_config.yaml) computes map metrics.
/// With truth and <recording_dir>/truth/dynamic_hits.csv the dynamic-object share of the map (against the same
/// scene's static surface). Missing truth, lidar truth, dynamic hits, deskew data or scene is not an error
/// (notes say what is missing); an unreadable map or a failing metric is an error only for files that exist
/// (the Status names the file).
Status EvaluateRun(const std::string& recording_dir, const std::string& slam_dir, const SlamRunResult& slam,
                   const std::string& scene_name_or_path, const RunEvaluationOptions& options, RunEvaluation* out);

}  // namespace rotolidar::bench
