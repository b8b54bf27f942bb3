#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>

#include "core/pipeline/voxel_map.hpp"
#include "core/registration/gicp_matcher.hpp"

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

// Removed points leave Points() and NumPoints(); the indices of the others stay valid. With one point per voxel
// the voxel takes a new point; with more, the removed point's place stays used. RemoveFar skips removed points.
TEST(VoxelMap, RemoveTombstonesAPointAndKeepsTheOtherIndices) {
  for (int per_voxel : {1, 2}) {
    SCOPED_TRACE(per_voxel);
    VoxelMap map(1.0, per_voxel);
    const std::vector<Eigen::Vector3d> pts = {{0.1, 0.1, 0.1}, {5.5, 0.5, 0.5}, {20.5, 0.5, 0.5}};
    std::vector<size_t> kept;
    map.Add(pts.data(), pts.size(), &kept);
    ASSERT_EQ(kept.size(), 3u);
    EXPECT_TRUE(map.Remove(kept[1]));
    EXPECT_FALSE(map.Remove(kept[1]));  // once
    EXPECT_EQ(map.NumPoints(), 2u);
    EXPECT_EQ(map.Points(), (std::vector<Eigen::Vector3d>{pts[0], pts[2]}));
    EXPECT_EQ(map.Point(kept[2]), pts[2]);
    const Eigen::Vector3d refill(5.4, 0.6, 0.5);
    std::vector<size_t> again;
    map.Add(&refill, 1, &again);
    ASSERT_EQ(again.size(), 1u);  // one per voxel: the voxel is free again; two: its second place is free
    EXPECT_EQ(map.Point(again[0]), refill);
    EXPECT_TRUE(map.Remove(again[0]));
    map.RemoveFar(Eigen::Vector3d::Zero(), 10.0);  // drops the far point and the removed ones
    EXPECT_EQ(map.Points(), (std::vector<Eigen::Vector3d>{pts[0]}));
    EXPECT_EQ(map.NumPoints(), 1u);
  }
}

// The reference: VoxelMap's rule (a point is kept when its voxel holds fewer than n points, all at least
// voxel / sqrt(n) away) over a std::map, without the full-voxel bit filter.
std::vector<Eigen::Vector3d> ReferenceVoxelMap(const std::vector<Eigen::Vector3d>& pts, double voxel, int n) {
  std::map<std::array<int64_t, 3>, std::vector<Eigen::Vector3d>> voxels;
  std::vector<Eigen::Vector3d> kept;
  const double min_sq = voxel * voxel / n;
  for (const auto& p : pts) {
    auto& v = voxels[{int64_t(std::floor(p.x() / voxel)), int64_t(std::floor(p.y() / voxel)),
                      int64_t(std::floor(p.z() / voxel))}];
    if (int(v.size()) >= n) continue;
    bool far = true;
    for (const auto& q : v) far = far && (q - p).squaredNorm() >= min_sq;
    if (!far) continue;
    v.push_back(p);
    kept.push_back(p);
  }
  return kept;
}

TEST(VoxelMap, FullVoxelFilterKeepsTheReferencePointsAcrossBlocksAndScans) {
  // Points on both sides of zero and across many 32-voxel blocks, added in several batches (scans) that revisit
  // the same voxels, for one and for several points per voxel.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  for (int n : {1, 3}) {
    VoxelMap map(0.05, n);
    std::vector<Eigen::Vector3d> all;
    for (int scan = 0; scan < 5; ++scan) {
      std::vector<Eigen::Vector3d> batch;
      for (int i = 0; i < 20000; ++i) batch.push_back(Eigen::Vector3d{u(rng), u(rng), 0.1 * u(rng)});
      map.Add(batch);
      all.insert(all.end(), batch.begin(), batch.end());
    }
    const std::vector<Eigen::Vector3d> expected = ReferenceVoxelMap(all, 0.05, n);
    ASSERT_EQ(map.NumPoints(), expected.size()) << "n = " << n;
    auto key = [](const Eigen::Vector3d& p) { return std::array<double, 3>{p.x(), p.y(), p.z()}; };
    std::vector<std::array<double, 3>> got, want;
    for (const auto& p : map.Points()) got.push_back(key(p));
    for (const auto& p : expected) want.push_back(key(p));
    std::sort(got.begin(), got.end());
    std::sort(want.begin(), want.end());
    EXPECT_EQ(got, want) << "n = " << n;
    // After RemoveFar the filter is rebuilt: re-adding everything adds nothing.
    map.RemoveFar(Eigen::Vector3d::Zero(), 3.0);
    const size_t after_remove = map.NumPoints();
    std::vector<Eigen::Vector3d> near;
    for (const auto& p : all)
      if (p.norm() < 2.5) near.push_back(p);
    map.Add(near);
    EXPECT_EQ(map.NumPoints(), after_remove) << "n = " << n;
  }
}

TEST(VoxelDownsample, KeepsOneCentroidPerVoxel) {
  std::vector<Eigen::Vector3d> pts{{0.1, 0.1, 0.1}, {0.3, 0.3, 0.3}, {1.5, 0.1, 0.1}};
  const auto out = VoxelDownsample(pts, 1.0);
  ASSERT_EQ(out.size(), 2u);
}

}  // namespace
}  // namespace rotolidar
