#include <gtest/gtest.h>

#include "core/pipeline/scan_matcher.hpp"
#include "core/pipeline/voxel_map.hpp"

namespace rotolidar {
namespace {

TEST(VoxelMap, CapsPointsPerVoxelAndRemovesFarVoxels) {
  VoxelMap map(1.0, 4);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) pts.emplace_back(0.05 + 0.09 * i, 0.05 + 0.09 * j, 0.5);  // one voxel
  pts.emplace_back(100.5, 0.5, 0.5);
  map.Add(pts);
  EXPECT_EQ(map.NumPoints(), 5u);  // 4 in the crowded voxel, 1 far away
  map.RemoveFar(Eigen::Vector3d::Zero(), 10.0);
  EXPECT_EQ(map.NumPoints(), 4u);
}

TEST(VoxelDownsample, KeepsOneCentroidPerVoxel) {
  std::vector<Eigen::Vector3d> pts{{0.1, 0.1, 0.1}, {0.3, 0.3, 0.3}, {1.5, 0.1, 0.1}};
  const auto out = VoxelDownsample(pts, 1.0);
  ASSERT_EQ(out.size(), 2u);
}

}  // namespace
}  // namespace rotolidar
