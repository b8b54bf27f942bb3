#pragma once
// The reference half shared by the voxel-filter tests: given each voxel's members (index order), the member
// nearest the voxel's centroid (double sum in index order / count, by (p - centroid).squaredNorm(), ties to the
// lower index), as sorted indices. The tests differ only in how they key the voxels.
#include <algorithm>
#include <cstddef>
#include <limits>
#include <map>
#include <vector>

#include <Eigen/Core>

namespace rotolidar::test {

template <typename Key>
std::vector<std::size_t> NearestToCentroids(const std::map<Key, std::vector<std::size_t>>& voxels,
                                            const std::vector<Eigen::Vector3f>& positions) {
  std::vector<std::size_t> kept;
  for (const auto& [key, members] : voxels) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const std::size_t i : members) sum += positions[i].cast<double>();
    const Eigen::Vector3d centroid = sum / static_cast<double>(members.size());
    std::size_t best = members.front();
    double best_sq = std::numeric_limits<double>::infinity();
    for (const std::size_t i : members) {
      const double sq = (positions[i].cast<double>() - centroid).squaredNorm();
      if (sq < best_sq) best_sq = sq, best = i;
    }
    kept.push_back(best);
  }
  std::sort(kept.begin(), kept.end());
  return kept;
}

}  // namespace rotolidar::test
