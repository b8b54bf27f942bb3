#pragma once
// The local feature map that scan-to-map registration matches against: the map-side features (FeatureSet
// less_sharp -> edge cloud, less_flat -> planar cloud) of the most recent keyframes, transformed into the map
// (world) frame, voxel-downsampled, with one exact nearest-neighbour index per cloud (CentroidIndex,
// core/registration/centroid_index.hpp: kd-trees that follow the centroids' changes).
//
// Downsampling: each keyframe's clouds are voxel-downsampled on their own (PCL VoxelGrid), and the map cloud is
// the VoxelGrid of the union of the live keyframes' downsampled clouds (per voxel: centroid of the keyframe
// points in it, intensity averaged). That union grid is maintained incrementally (VoxelCentroidTable,
// voxel_centroids.hpp): a new keyframe adds its points' sums, a dropped one subtracts exactly its own, so
// AddKeyframe costs ~ the keyframe's size (plus an occasional rebuild of the index), not a re-merge of the
// window. Cloud order: voxel creation order (deterministic for a given keyframe sequence).
//
// Policy: a scan becomes a keyframe when the map is empty or its pose is at least keyframe_distance_m or
// keyframe_angle_rad away from the newest keyframe (NeedsKeyframe; the caller decides and calls AddKeyframe).
// The map is bounded: keyframes beyond max_keyframes (oldest first) or farther than max_distance_m from the newest
// keyframe are dropped. Each AddKeyframe updates the downsampled clouds and their indices.
//
// Ownership: owns copies of its clouds. Thread-safety: none (one thread at a time, also for const searches).
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "core/features/feature_set.hpp"
#include "core/types/geometry.hpp"

namespace rotolidar {

struct LocalMapConfig {
  double keyframe_distance_m = 1.0;  ///< new keyframe after this much translation from the newest one [m]
  double keyframe_angle_rad = 0.2;   ///< ... or this much rotation [rad] (~11 deg)
  /// Sliding window by count. 160: a rotary rig keys every other scan (EstimatorConfig::keyframe_every_scans),
  /// so 160 keyframes hold the last ~32 s (~13 rotor turns). Along an axis the scans see only weakly (the far
  /// end walls of a corridor) a map that remembers longer drifts less: corridor 40 s, typical, seeds 1-10,
  /// median / p90 / worst ATE 0.0269 / 0.0389 / 0.0493 m with 40, 0.0237 / 0.0326 / 0.0367 with 80, 0.0219 /
  /// 0.0316 / 0.0474 with 100, 0.0215 / 0.0327 / 0.0343 with 160, 0.0229 / 0.0325 / 0.0363 with 320; the other
  /// scenes move by -22 % to +8 %, the per-scan time by ~+5 %.
  int max_keyframes = 160;
  double max_distance_m = 80.0;      ///< keyframes farther than this from the newest keyframe are dropped [m]
  double edge_voxel_m = 0.2;         ///< voxel size of the map's edge cloud [m]
  double planar_voxel_m = 0.2;       ///< voxel size of the map's planar cloud [m] (a rotary fan needs a denser map)
  bool Validate(std::string* error) const;  ///< false with the offending field named in *error
};

enum class FeatureKind { kEdge, kPlanar };

class LocalMap {
 public:
  static constexpr int kMaxNearest = 32;  ///< the largest k of Nearest
  /// `config` must Validate (a programmer error otherwise: ROTOLIDAR_CHECK throws InternalError).
  explicit LocalMap(const LocalMapConfig& config = LocalMapConfig());
  ~LocalMap();
  LocalMap(LocalMap&&) noexcept;
  LocalMap& operator=(LocalMap&&) noexcept;
  LocalMap(const LocalMap&) = delete;
  LocalMap& operator=(const LocalMap&) = delete;

  /// True when the map has no keyframe or T_map_scan moved/turned enough from the newest keyframe.
  bool NeedsKeyframe(const Pose3& T_map_scan) const;
  /// Adds `features.less_sharp` / `features.less_flat` (scan frame) at T_map_scan as a keyframe, applies the
  /// window bounds and updates clouds and indices. Empty feature clouds are allowed.
  void AddKeyframe(const FeatureSet& features, const Pose3& T_map_scan);
  void Clear();

  /// Up to k nearest map points of `kind` to p_map (map frame), nearest first, into *points (map frame [m]) and
  /// *sq_dist_m2 (squared distances [m^2], float as the tree computes them). Returns how many were found
  /// (0 for an empty cloud); 1 <= k <= kMaxNearest (checked). Both vectors are resized, never shrunk in capacity.
  /// Only points with squared distance < max_sq_dist_m2 count (default: all): fewer than k may come back.
  /// With `views`, also each point's mean unit view vector (map frame, point -> the keyframes' sensor positions
  /// that saw it; length ~1 when seen from one side, ~0 when both sides of a thin wall share a voxel).
  int Nearest(FeatureKind kind, const Eigen::Vector3d& p_map, int k, std::vector<Eigen::Vector3d>* points,
              std::vector<float>* sq_dist_m2, float max_sq_dist_m2 = std::numeric_limits<float>::infinity(),
              std::vector<Eigen::Vector3f>* views = nullptr) const;

  /// The downsampled cloud of `kind` in the map frame (intensity: averaged curvature of the merged points),
  /// exported on the first call after a change (valid until the next AddKeyframe / Clear).
  const pcl::PointCloud<pcl::PointXYZI>& cloud(FeatureKind kind) const;
  std::vector<Pose3> keyframe_poses() const;  ///< T_map_scan of the kept keyframes, oldest first
  size_t num_keyframes() const;
  bool empty() const { return num_keyframes() == 0; }
  const LocalMapConfig& config() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rotolidar
