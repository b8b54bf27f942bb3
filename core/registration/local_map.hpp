#pragma once
// The local feature map that scan-to-map registration matches against: the map-side features (FeatureSet
// less_sharp -> edge cloud, less_flat -> planar cloud) of the most recent keyframes, transformed into the map
// (world) frame, voxel-downsampled, with one kd-tree per cloud (PCL KdTreeFLANN, kept inside the .cpp).
//
// Policy: a scan becomes a keyframe when the map is empty or its pose is at least keyframe_distance_m or
// keyframe_angle_rad away from the newest keyframe (NeedsKeyframe; the caller decides and calls AddKeyframe).
// The map is bounded: keyframes beyond max_keyframes (oldest first) or farther than max_distance_m from the newest
// keyframe are dropped. Each AddKeyframe rebuilds the downsampled clouds and kd-trees (cost ~ map size).
//
// Ownership: owns copies of its clouds. Thread-safety: none (one thread at a time, also for const searches).
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
  int max_keyframes = 30;            ///< sliding window by count
  double max_distance_m = 80.0;      ///< keyframes farther than this from the newest keyframe are dropped [m]
  double edge_voxel_m = 0.2;         ///< voxel size of the map's edge cloud [m]
  double planar_voxel_m = 0.4;       ///< voxel size of the map's planar cloud [m]
  bool Validate(std::string* error) const;  ///< false with the offending field named in *error
};

enum class FeatureKind { kEdge, kPlanar };

class LocalMap {
 public:
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
  /// window bounds and rebuilds clouds and kd-trees. Empty feature clouds are allowed.
  void AddKeyframe(const FeatureSet& features, const Pose3& T_map_scan);
  void Clear();

  /// Up to k nearest map points of `kind` to p_map (map frame), nearest first, into *points (map frame [m]) and
  /// *sq_dist_m2 (squared distances [m^2]). Returns how many were found (0 for an empty cloud); k >= 1.
  int Nearest(FeatureKind kind, const Eigen::Vector3d& p_map, int k, std::vector<Eigen::Vector3d>* points,
              std::vector<float>* sq_dist_m2) const;

  /// The downsampled cloud of `kind` in the map frame (intensity: averaged curvature of the merged points).
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
