#pragma once
// How much of the moving objects (a scene's `dynamic:` walkers and cars) the SLAM dense map kept: the sim's
// truth lists every LiDAR return the packets carried from a dynamic object (<recording>/truth/dynamic_hits.csv,
// sim/truth/truth.hpp); a map point counts as dynamic when it lies off the static scene surface and next to such
// a return. Definitions and the thresholds' reasons: docs/metrics.md, 'Dynamic objects in the map'.
//
// Frames: hits and map points in the scene's world frame [m] (a SLAM map moved there by LoadMapInSceneFrame).
// Determinism: no randomness; equal inputs give equal outputs. Thread safety: the functions share no state.
#include <cstddef>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include "core/util/status.hpp"
#include "sim/truth/truth.hpp"

namespace rotolidar::bench {

class SurfaceDistance;

struct DynamicShareConfig {
  /// Voxel edge [m] the seen returns are counted in: the dense map's voxel (EstimatorConfig's map voxel,
  /// 0.05 m by default). share_of_seen counts voxels on both sides (a map point counts for its nearest return's
  /// voxel), so the map's noise spreading one surface over several voxels cannot push it above 1.
  double voxel_m = 0.05;
  /// A map point this close to the static scene surface [m] is static whatever else is near it. Above the map's
  /// typical noise (5x the twin's 3 cm range noise, ~3x the map-to-truth median of 2-5 cm of its runs), so wall
  /// and floor points next to a walker's feet or a parked car are not counted.
  double static_clearance_m = 0.15;
  /// A map point off the static surface is dynamic when a dynamic return lies within this [m]: two voxels of
  /// the default map, room for the map's own voxelisation and noise without reaching far beyond the object.
  double hit_radius_m = 0.10;

  /// True when usable; otherwise false with the field named in *error.
  bool Validate(std::string* error) const;
};

/// The counts of one moving object (the scene's `dynamic:` entry object_id): which object a map leaks.
struct DynamicObjectShare {
  int object_id = 0;                   ///< index into the scene's dynamic objects
  std::string name;                    ///< its name in the scene, when the caller knows it (else empty)
  std::size_t returns_seen = 0;
  std::size_t voxels_seen = 0;
  std::size_t map_points_dynamic = 0;  ///< dynamic map points whose nearest return is this object's
  std::size_t voxels_reached = 0;
  double share_of_seen = 0.0;          ///< voxels_reached / voxels_seen
};

struct DynamicShare {
  std::size_t returns_seen = 0;        ///< dynamic returns in the truth
  std::size_t voxels_seen = 0;         ///< distinct voxels (voxel_m) those returns occupy
  std::size_t map_points = 0;          ///< map points scored
  std::size_t map_points_dynamic = 0;  ///< off the static surface (> static_clearance_m) and near a return
  std::size_t voxels_reached = 0;      ///< seen voxels holding the nearest return of a dynamic map point
  double share_of_seen = 0.0;          ///< voxels_reached / voxels_seen (<= 1); 0 when nothing was seen
  double share_of_map = 0.0;           ///< map_points_dynamic / map_points; 0 for an empty map
  std::vector<DynamicObjectShare> per_object;  ///< the same per object seen, by object_id
};

/// Distance [m] from a point [scene world frame] to the static scene surface; may return any value above
/// `at_least_m` when the surface is farther than that.
using StaticDistanceFn = std::function<double(const Eigen::Vector3d& p_world, double at_least_m)>;

/// Counts the dynamic share of `map_world` against `hits`. `static_distance` is asked only about map points
/// within hit_radius_m of a return. Fails (naming the field) on an invalid config or a missing function.
Status ComputeDynamicShare(const std::vector<sim::DynamicHitSample>& hits,
                           const std::vector<Eigen::Vector3f>& map_world, const StaticDistanceFn& static_distance,
                           const DynamicShareConfig& config, DynamicShare* out);

/// The static distance of a scene's static mesh (SurfaceDistance over sim::BuildMesh), for ComputeDynamicShare;
/// `surface` must outlive the function.
StaticDistanceFn StaticDistanceOf(const SurfaceDistance& surface);

/// The "dynamic" object of metrics.json: the counts, the shares, the thresholds used and `per_object`.
void ToJson(const DynamicShare& share, const DynamicShareConfig& config, nlohmann::json* out);

/// One line: "dynamic objects: N returns seen in V voxels; the dense map reached R of those voxels (x.xx %) with M
/// points (y.yy % of the map)".
std::string DynamicShareLine(const DynamicShare& share);
/// One line per object seen: "  NAME (id K): R returns, V voxels; the map reached X (x.xx %) with M points".
std::string DynamicObjectLines(const DynamicShare& share);

}  // namespace rotolidar::bench
