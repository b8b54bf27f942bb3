// The incremental local map against its definition (a PCL VoxelGrid over the union of the live keyframes'
// downsampled clouds), exact removal of a dropped keyframe, determinism, and the kd-tree against brute force.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <pcl/common/transforms.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/kdtree/kdtree_flann.h>

#include "core/registration/kd_tree.hpp"
#include "core/registration/local_map.hpp"
#include "core/registration/voxel_centroids.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZI>;

Cloud VoxelGrid(const Cloud& in, double voxel_m) {
  Cloud out;
  if (in.empty()) return out;
  pcl::VoxelGrid<pcl::PointXYZI> grid;
  grid.setInputCloud(Cloud::ConstPtr(new Cloud(in)));
  grid.setLeafSize(float(voxel_m), float(voxel_m), float(voxel_m));
  grid.filter(out);
  return out;
}

/// A random scan-like feature cloud: points on a few planes of a 12 x 10 x 3 m room plus noise, curvature as
/// intensity, in the scan frame.
Cloud RoomCloud(RandomStream* rng, int n) {
  Cloud c;
  for (int i = 0; i < n; ++i) {
    pcl::PointXYZI p;
    const double u = rng->Uniform() * 12 - 6, v = rng->Uniform() * 10 - 5, w = rng->Uniform() * 3;
    switch (i % 4) {
      case 0: p.x = float(u), p.y = float(v), p.z = 0.0f; break;            // floor
      case 1: p.x = 6.0f, p.y = float(v), p.z = float(w); break;            // wall
      case 2: p.x = float(u), p.y = -5.0f, p.z = float(w); break;           // wall
      default: p.x = float(u * 0.3), p.y = float(v * 0.3), p.z = float(w); break;  // clutter
    }
    p.x += float(rng->Normal() * 0.01);
    p.intensity = float(rng->Uniform());
    c.push_back(p);
  }
  return c;
}

Pose3 Walk(int i) {
  return MakePose(Eigen::Vector3d(0.3 * i, 0.1 * std::sin(i), 0.02 * i),
                  Eigen::Quaterniond(Eigen::AngleAxisd(0.05 * i, Eigen::Vector3d::UnitZ())));
}

/// Voxel index of a centroid (PCL's float indexing) -> the centroid: an order-free view of a downsampled cloud.
std::map<std::tuple<int, int, int>, pcl::PointXYZI> ByVoxel(const Cloud& c, double voxel_m) {
  std::map<std::tuple<int, int, int>, pcl::PointXYZI> m;
  const float inv = 1.0f / float(voxel_m);
  for (const auto& p : c)
    m[{int(std::floor(p.x * inv)), int(std::floor(p.y * inv)), int(std::floor(p.z * inv))}] = p;
  return m;
}

void ExpectSameVoxels(const Cloud& got, const Cloud& want, double voxel_m) {
  ASSERT_EQ(got.size(), want.size());
  const auto g = ByVoxel(got, voxel_m), w = ByVoxel(want, voxel_m);
  ASSERT_EQ(g.size(), got.size()) << "two centroids in one voxel";
  for (const auto& [key, p] : w) {
    const auto it = g.find(key);
    ASSERT_NE(it, g.end());
    // float precision: PCL sums in float, the table in double
    EXPECT_NEAR(it->second.x, p.x, 2e-6f * (1.0f + std::abs(p.x)));
    EXPECT_NEAR(it->second.y, p.y, 2e-6f * (1.0f + std::abs(p.y)));
    EXPECT_NEAR(it->second.z, p.z, 2e-6f * (1.0f + std::abs(p.z)));
    EXPECT_NEAR(it->second.intensity, p.intensity, 2e-6f);
  }
}

TEST(LocalMapIncremental, EqualsVoxelGridOfTheLiveKeyframesUnionThroughTheWindow) {
  RandomStream rng(5, "test.registration.local_map_incremental");
  LocalMapConfig config;
  config.max_keyframes = 4;
  config.planar_voxel_m = 0.2;
  LocalMap map(config);
  std::vector<Cloud> edge_kf, planar_kf;  // map frame, per keyframe downsampled, as the map defines them
  for (int i = 0; i < 9; ++i) {
    FeatureSet f;
    f.less_flat = RoomCloud(&rng, 3000);
    f.less_sharp = RoomCloud(&rng, 300);
    const Eigen::Matrix4f M = Walk(i).matrix().cast<float>();
    Cloud e, p;
    pcl::transformPointCloud(f.less_sharp, e, M);
    pcl::transformPointCloud(f.less_flat, p, M);
    edge_kf.push_back(VoxelGrid(e, config.edge_voxel_m));
    planar_kf.push_back(VoxelGrid(p, config.planar_voxel_m));
    map.AddKeyframe(f, Walk(i));
    Cloud edge_union, planar_union;
    for (size_t k = edge_kf.size() - map.num_keyframes(); k < edge_kf.size(); ++k) {
      edge_union += edge_kf[k];
      planar_union += planar_kf[k];
    }
    SCOPED_TRACE("keyframe " + std::to_string(i));
    ExpectSameVoxels(map.cloud(FeatureKind::kEdge), VoxelGrid(edge_union, config.edge_voxel_m), config.edge_voxel_m);
    ExpectSameVoxels(map.cloud(FeatureKind::kPlanar), VoxelGrid(planar_union, config.planar_voxel_m),
                     config.planar_voxel_m);
  }
  EXPECT_EQ(map.num_keyframes(), 4u);
}

TEST(VoxelCentroidTable, RemovingASetRestoresTheTableExactly) {
  RandomStream rng(6, "test.registration.voxel_table");
  const Cloud a = RoomCloud(&rng, 2000), b = RoomCloud(&rng, 2000);
  VoxelCentroidTable only_a(0.2), both(0.2);
  only_a.Add(a);
  both.Add(a);
  both.Add(b);
  EXPECT_GT(both.num_voxels(), only_a.num_voxels());
  both.Remove(b);
  Cloud want, got;
  only_a.Centroids(&want);
  both.Centroids(&got);
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < got.size(); ++i) {  // same creation order, and bit-identical sums after the subtraction
    EXPECT_EQ(got[i].x, want[i].x);
    EXPECT_EQ(got[i].y, want[i].y);
    EXPECT_EQ(got[i].z, want[i].z);
    EXPECT_EQ(got[i].intensity, want[i].intensity);
  }
  both.Remove(a);
  EXPECT_EQ(both.num_voxels(), 0u);
  both.Centroids(&got);
  EXPECT_TRUE(got.empty());
  EXPECT_THROW(both.Remove(a), std::exception);  // removing what is not there is a programmer error
}

TEST(VoxelCentroidTable, SlidingWindowMatchesAFreshTableThroughGrowthAndCompaction) {
  RandomStream rng(9, "test.registration.voxel_table_window");
  std::vector<Cloud> sets;
  VoxelCentroidTable window(0.1);
  for (int i = 0; i < 12; ++i) {
    Cloud c = RoomCloud(&rng, 6000);
    for (auto& p : c) p.x += float(2.0 * i);  // the window moves on: old voxels die, compaction runs
    sets.push_back(c);
    window.Add(c);
    if (i >= 3) window.Remove(sets[size_t(i - 3)]);
    VoxelCentroidTable fresh(0.1);
    for (int k = std::max(0, i - 2); k <= i; ++k) fresh.Add(sets[size_t(k)]);
    Cloud got, want;
    window.Centroids(&got);
    fresh.Centroids(&want);
    SCOPED_TRACE("set " + std::to_string(i));
    EXPECT_EQ(window.num_voxels(), fresh.num_voxels());
    ExpectSameVoxels(got, want, 0.1);
  }
}

TEST(LocalMapIncremental, SameKeyframesGiveTheSameCloudInTheSameOrder) {
  auto build = [] {
    RandomStream rng(7, "test.registration.local_map_determinism");
    LocalMapConfig config;
    config.max_keyframes = 3;
    LocalMap map(config);
    for (int i = 0; i < 6; ++i) {
      FeatureSet f;
      f.less_flat = RoomCloud(&rng, 1500);
      map.AddKeyframe(f, Walk(i));
    }
    return map.cloud(FeatureKind::kPlanar);
  };
  const Cloud a = build(), b = build();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(a[i].x == b[i].x && a[i].y == b[i].y && a[i].z == b[i].z);
}

TEST(KdTree3f, NearestIsExactAgainstBruteForceAndFlann) {
  RandomStream rng(8, "test.registration.kd_tree");
  const Cloud cloud = VoxelGrid(RoomCloud(&rng, 40000), 0.2);
  std::vector<float> xyz;
  for (const auto& p : cloud) xyz.insert(xyz.end(), {p.x, p.y, p.z});
  KdTree3f tree;
  tree.Build(xyz);
  ASSERT_EQ(tree.size(), cloud.size());
  pcl::KdTreeFLANN<pcl::PointXYZI> flann;
  flann.setInputCloud(Cloud::ConstPtr(new Cloud(cloud)));
  const int k = 6;
  int idx[KdTree3f::kMaxK];
  float sq[KdTree3f::kMaxK];
  std::vector<int> flann_idx;
  std::vector<float> flann_sq;
  for (int trial = 0; trial < 300; ++trial) {
    const float q[3] = {float(rng.Uniform() * 16 - 8), float(rng.Uniform() * 14 - 7), float(rng.Uniform() * 4 - 0.5)};
    ASSERT_EQ(tree.Nearest(q, k, idx, sq), k);
    std::vector<float> brute;
    for (const auto& p : cloud) {
      const float dx = q[0] - p.x, dy = q[1] - p.y, dz = q[2] - p.z;
      brute.push_back(dx * dx + dy * dy + dz * dz);
    }
    std::sort(brute.begin(), brute.end());
    pcl::PointXYZI qp;
    qp.x = q[0], qp.y = q[1], qp.z = q[2];
    flann.nearestKSearch(qp, k, flann_idx, flann_sq);
    for (int j = 0; j < k; ++j) {
      EXPECT_EQ(sq[j], brute[size_t(j)]);  // the same float arithmetic: exact
      EXPECT_EQ(sq[j], flann_sq[size_t(j)]);
      const auto& p = cloud[size_t(idx[j])];
      const float dx = q[0] - p.x, dy = q[1] - p.y, dz = q[2] - p.z;
      EXPECT_EQ(dx * dx + dy * dy + dz * dz, sq[j]);  // the index belongs to the distance
    }
  }
  // The points come back with their indices; a search bounded just above the farthest of a nearby query's k + 1
  // (how KthSquaredDistance re-searches) returns exactly the unbounded result, order included.
  float pts[3 * KdTree3f::kMaxK];
  int near_idx[KdTree3f::kMaxK], bounded_idx[KdTree3f::kMaxK];
  float near_sq[KdTree3f::kMaxK], bounded_sq[KdTree3f::kMaxK];
  for (int trial = 0; trial < 300; ++trial) {
    const float q[3] = {float(rng.Uniform() * 16 - 8), float(rng.Uniform() * 14 - 7), float(rng.Uniform() * 4 - 0.5)};
    ASSERT_EQ(tree.Nearest(q, k + 1, idx, sq, std::numeric_limits<float>::infinity(), pts), k + 1);
    const float moved[3] = {q[0] + 0.03f, q[1] - 0.02f, q[2] + 0.01f};
    ASSERT_EQ(tree.Nearest(moved, k + 1, near_idx, near_sq), k + 1);
    float farthest = 0.0f;
    for (int j = 0; j <= k; ++j) {
      const auto& p = cloud[size_t(idx[j])];
      EXPECT_TRUE(pts[3 * j] == p.x && pts[3 * j + 1] == p.y && pts[3 * j + 2] == p.z);
      const float dx = moved[0] - p.x, dy = moved[1] - p.y, dz = moved[2] - p.z;
      farthest = std::max(farthest, dx * dx + dy * dy + dz * dz);
    }
    const float bound = std::nextafter(farthest, std::numeric_limits<float>::infinity());
    ASSERT_EQ(tree.Nearest(moved, k + 1, bounded_idx, bounded_sq, bound), k + 1);
    for (int j = 0; j <= k; ++j) EXPECT_TRUE(bounded_idx[j] == near_idx[j] && bounded_sq[j] == near_sq[j]);
  }
  // Fewer points than k, and an empty tree.
  KdTree3f small;
  small.Build({1.0f, 2.0f, 3.0f, 0.0f, 0.0f, 0.0f});
  const float q0[3] = {0.0f, 0.0f, 0.1f};
  ASSERT_EQ(small.Nearest(q0, 5, idx, sq), 2);
  EXPECT_EQ(idx[0], 1);
  EXPECT_EQ(idx[1], 0);
  KdTree3f empty;
  empty.Build({});
  EXPECT_EQ(empty.Nearest(q0, 3, idx, sq), 0);
}

}  // namespace
}  // namespace rotolidar
