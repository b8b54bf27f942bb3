#pragma once
// A sparse voxel map of world points (KISS-ICP's voxel hash map): at most `max_points_per_voxel` points per
// voxel, so density stays bounded however long the rig dwells. Used as the local map (registration target)
// and as the global map (the dense output).
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

namespace rotolidar {

class VoxelMap {
 public:
  /// voxel_size_m > 0; max_points_per_voxel >= 1.
  VoxelMap(double voxel_size_m, int max_points_per_voxel);

  /// Adds world points; a point is kept when its voxel has room and it is at least voxel/sqrt(n) from the
  /// voxel's points already there (uniform spread inside the voxel).
  void Add(const std::vector<Eigen::Vector3d>& p_world);
  /// Removes voxels whose centre is farther than max_distance_m from `center_world`.
  void RemoveFar(const Eigen::Vector3d& center_world, double max_distance_m);
  /// All points (order unspecified but deterministic for the same insertion sequence).
  std::vector<Eigen::Vector3d> Points() const;
  size_t NumPoints() const;
  bool Empty() const { return voxels_.empty(); }
  double voxel_size_m() const { return voxel_size_m_; }

 private:
  struct Key {
    int32_t x, y, z;
    bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  struct KeyHash {
    size_t operator()(const Key& k) const {
      return (size_t(uint32_t(k.x)) * 73856093u) ^ (size_t(uint32_t(k.y)) * 19349669u) ^
             (size_t(uint32_t(k.z)) * 83492791u);
    }
  };
  Key KeyOf(const Eigen::Vector3d& p) const;

  double voxel_size_m_;
  int max_points_per_voxel_;
  double min_spacing_m_;
  std::unordered_map<Key, std::vector<Eigen::Vector3d>, KeyHash> voxels_;
  std::vector<Key> insertion_order_;  // keeps Points() deterministic
};

}  // namespace rotolidar
