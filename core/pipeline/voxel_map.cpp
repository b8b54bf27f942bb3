#include "core/pipeline/voxel_map.hpp"

#include <cmath>

#include "core/util/log.hpp"

namespace rotolidar {

VoxelMap::VoxelMap(double voxel_size_m, int max_points_per_voxel)
    : voxel_size_m_(voxel_size_m),
      max_points_per_voxel_(max_points_per_voxel),
      min_spacing_m_(voxel_size_m / std::sqrt(double(max_points_per_voxel))) {
  ROTOLIDAR_CHECK(voxel_size_m > 0 && max_points_per_voxel >= 1, "bad VoxelMap parameters");
}

VoxelMap::Key VoxelMap::KeyOf(const Eigen::Vector3d& p) const {
  return {int32_t(std::floor(p.x() / voxel_size_m_)), int32_t(std::floor(p.y() / voxel_size_m_)),
          int32_t(std::floor(p.z() / voxel_size_m_))};
}

void VoxelMap::Add(const std::vector<Eigen::Vector3d>& p_world) {
  const double min_sq = min_spacing_m_ * min_spacing_m_;
  for (const Eigen::Vector3d& p : p_world) {
    const Key key = KeyOf(p);
    auto [it, inserted] = voxels_.try_emplace(key);
    if (inserted) insertion_order_.push_back(key);
    std::vector<Eigen::Vector3d>& pts = it->second;
    if (int(pts.size()) >= max_points_per_voxel_) continue;
    bool far_enough = true;
    for (const auto& q : pts) far_enough = far_enough && (q - p).squaredNorm() >= min_sq;
    if (far_enough) pts.push_back(p);
  }
}

void VoxelMap::RemoveFar(const Eigen::Vector3d& center_world, double max_distance_m) {
  const double max_sq = max_distance_m * max_distance_m;
  std::vector<Key> kept;
  kept.reserve(insertion_order_.size());
  for (const Key& key : insertion_order_) {
    auto it = voxels_.find(key);
    if (it->second.empty() || (it->second.front() - center_world).squaredNorm() > max_sq)
      voxels_.erase(it);
    else
      kept.push_back(key);
  }
  insertion_order_.swap(kept);
}

std::vector<Eigen::Vector3d> VoxelMap::Points() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(NumPoints());
  for (const Key& key : insertion_order_) {
    const auto& pts = voxels_.at(key);
    out.insert(out.end(), pts.begin(), pts.end());
  }
  return out;
}

size_t VoxelMap::NumPoints() const {
  size_t n = 0;
  for (const auto& kv : voxels_) n += kv.second.size();
  return n;
}

}  // namespace rotolidar
