#pragma once
// Map metrics against the scene's truth (docs/metrics.md defines each one): coverage and completeness of the
// scene's surfaces per class, point-density uniformity, map-to-truth distance per point, and the measured vs
// true dimensions of the scene's annotated doors, windows and columns. One entry point: ComputeMapMetrics.
//
// Frames: every point here is in the scene's world frame [m]. A SLAM map lives in the SLAM world (the base
// frame at the first scan); LoadMapInSceneFrame moves it into the scene frame with the truth trajectory.
// Determinism: no randomness; surface samples sit on a fixed grid per triangle, so equal inputs give equal
// outputs. Thread safety: the functions share no state.
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json_fwd.hpp>

#include "bench/metrics/coverage.hpp"
#include "bench/metrics/geometry_accuracy.hpp"
#include "core/types/trajectory.hpp"
#include "core/util/status.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::bench {

struct MapMetricsConfig {
  double coverage_distance_m = 0.05;  ///< a surface sample is covered when a map point lies within this
  double sample_spacing_m = 0.05;     ///< grid spacing of the surface samples (each stands for spacing^2 m^2)
  double density_cell_m = 0.5;        ///< edge of the cubic cells that group surface samples for density
  /// Region of interest [world]: only surface samples inside count for coverage/density; map points outside
  /// are still measured for map-to-truth. Empty box (default) = the whole scene.
  Eigen::AlignedBox3d region;
  /// Visibility (completeness): viewpoints [world] that make a sample observable when one of them lies within
  /// [min_range_m, max_range_m] with a clear line of sight (Embree rays). Empty: completeness is not computed.
  std::vector<Eigen::Vector3d> viewpoints_world;
  double visibility_min_range_m = 0.4;  ///< VLP-16 minimum range
  double visibility_max_range_m = 30.0;  ///< lidar range considered reliable for a map [m]
  double viewpoint_spacing_m = 0.25;     ///< viewpoints closer than this to the previous kept one are dropped
  ElementFitConfig elements;             ///< door/window/column fitting (geometry_accuracy.hpp)
  bool compute_elements = true;
  bool keep_per_point = true;   ///< fill MapMetrics::point_distance_m (the report colours the map by it)
  bool keep_samples = true;     ///< fill MapMetrics::samples (coverage pictures)

  bool Validate(std::string* error) const;
};

/// Summary statistics of a distance array [m]; count 0 = no data (other fields 0).
struct DistanceStats {
  size_t count = 0;
  double median_m = 0.0, mean_m = 0.0, rmse_m = 0.0, p95_m = 0.0, max_m = 0.0;
  double fraction_within_m = 0.0;  ///< share of values <= MapMetricsConfig::coverage_distance_m
};

struct MapMetrics {
  size_t map_points = 0;
  size_t surface_samples = 0;   ///< samples inside the region
  CoverageResult coverage;      ///< per class + total; completeness when viewpoints were given
  DensityResult density;        ///< points per m^2 over surface cells
  DistanceStats map_to_truth;   ///< every map point's exact distance to the nearest scene triangle
  /// Per map point, same order as the input: distance to the nearest static scene triangle [m].
  std::vector<float> point_distance_m;
  /// Per surface sample (coverage pictures): position [world], class, covered and visible flags.
  std::vector<SurfaceSample> samples;
  std::vector<ElementMeasurement> elements;  ///< one per Scene::elements entry, in order
  ElementSummary element_summary;            ///< RMSE of width/height errors over the measured elements
};

/// Computes every metric. Fails (Status naming the field) on an invalid config, an empty map, a scene whose
/// mesh is empty, or an Embree error. Elements that cannot be fitted (too few points) are reported with
/// measured = false and left out of the RMSE.
/// `progress` (optional) follows the visibility pass, the long part (minutes on long runs: docs/metrics.md,
/// 'Coverage and completeness').
Status ComputeMapMetrics(const sim::Scene& scene, const std::vector<Eigen::Vector3f>& map_world,
                         const MapMetricsConfig& config, MapMetrics* out,
                         const std::function<void(double)>& progress = nullptr);

/// The "map" object of metrics.json (per-point and per-sample arrays are not written).
void ToJson(const MapMetrics& metrics, nlohmann::json* out);

/// Prints the metrics as tables (coverage per class, density, map-to-truth, elements).
void PrintMapMetrics(const MapMetrics& metrics, std::ostream& os);

/// How a SLAM map (SLAM world = base at the first scan) is brought into the scene frame.
enum class MapAlignment {
  kFirstPose,  ///< T_scene_slam = T_scene_base(t0) * T_slam_base(t0)^-1 at the estimate's first stamp
  kSe3,        ///< SE(3) Umeyama of the estimated positions onto the truth interpolated at their stamps
};
bool ParseMapAlignment(const std::string& name, MapAlignment* out);

/// T_scene_slam from the truth trajectory (T_scene_base, e.g. <recording>/truth/base.tum) and the estimate
/// (T_slam_base). Fails when they do not overlap in time or the alignment is degenerate.
Status MapToSceneTransform(const Trajectory& truth, const Trajectory& estimate, MapAlignment alignment,
                           Eigen::Isometry3d* T_scene_slam);

/// Reads a map (.ply/.pcd, core/io/point_cloud_io.hpp) and maps it by T_scene_map into the scene frame.
Status LoadMapInSceneFrame(const std::string& path, const Eigen::Isometry3d& T_scene_map,
                           std::vector<Eigen::Vector3f>* map_world);

}  // namespace rotolidar::bench
