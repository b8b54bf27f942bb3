// The incremental centroid index against brute force: a kd-tree whose points move or are hidden, and a
// CentroidIndex that follows a sliding window of point sets through overflow, main rebuilds, table growth and
// compaction. Distances must be bit-identical to a brute-force search (same float arithmetic).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "core/registration/centroid_index.hpp"
#include "core/registration/kd_tree.hpp"
#include "core/registration/voxel_centroids.hpp"
#include "core/util/log.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZI>;

float SqDist(const float q[3], const float p[3]) {
  const float dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2];
  return dx * dx + dy * dy + dz * dz;
}

/// Points built on a 0.2 m grid, then moved by up to `move_m` per axis (or hidden), searched against brute force.
void ExpectExactAfterMoves(float move_m) {
  RandomStream rng(3, "test.registration.kd_tree_moves");
  const float leaf = 0.2f;
  std::vector<float> built;  // cell centres of a 10 x 8 x 3 m block
  for (int i = 0; i < 6000; ++i)
    for (float extent : {10.0f, 8.0f, 3.0f})
      built.push_back((std::floor(float(rng.Uniform()) * extent / leaf) + 0.5f) * leaf);
  KdTree3f tree;
  tree.Build(built);
  const int n = int(tree.size());
  std::vector<float> now = built;
  std::vector<bool> hidden(size_t(n), false);
  for (int i = 0; i < n; ++i) {
    if (i % 10 == 3) {
      tree.Hide(i);
      hidden[size_t(i)] = true;
      continue;
    }
    float p[3];
    for (int d = 0; d < 3; ++d) p[d] = built[size_t(3 * i + d)] + float(rng.Uniform() * 2 - 1) * move_m;
    tree.Move(i, p);
    std::copy(p, p + 3, now.begin() + 3 * i);
  }
  tree.Refit();
  const int k = 8;
  int idx[KdTree3f::kMaxK];
  float sq[KdTree3f::kMaxK], xyz[3 * KdTree3f::kMaxK];
  for (int trial = 0; trial < 400; ++trial) {
    const float q[3] = {float(rng.Uniform() * 12 - 1), float(rng.Uniform() * 10 - 1), float(rng.Uniform() * 5 - 1)};
    ASSERT_EQ(tree.Nearest(q, k, idx, sq, std::numeric_limits<float>::infinity(), xyz), k);
    std::vector<float> brute;
    for (int i = 0; i < n; ++i)
      if (!hidden[size_t(i)]) brute.push_back(SqDist(q, &now[size_t(3 * i)]));
    std::sort(brute.begin(), brute.end());
    for (int j = 0; j < k; ++j) {
      EXPECT_EQ(sq[j], brute[size_t(j)]);
      EXPECT_FALSE(hidden[size_t(idx[j])]);
      EXPECT_EQ(SqDist(q, &now[size_t(3 * idx[j])]), sq[j]);  // index, point and distance belong together
      EXPECT_EQ(SqDist(q, xyz + 3 * j), sq[j]);
    }
  }
  // A hidden point comes back when moved again, wherever it goes.
  const float back[3] = {-3.0f, 20.0f, 1.0f};  // point 3 is hidden
  tree.Move(3, back);
  tree.Refit();
  ASSERT_EQ(tree.Nearest(back, 1, idx, sq), 1);
  EXPECT_EQ(idx[0], 3);
  EXPECT_EQ(sq[0], 0.0f);
}

TEST(KdTree3fMoves, MovedAndHiddenPointsAreSearchedExactly) {
  ExpectExactAfterMoves(0.1f);  // within the cell: how voxel centroids drift
  // Moves far beyond the spacing: the children's bounds overlap widely, which only the search's clamped
  // far-side distance handles.
  ExpectExactAfterMoves(0.6f);
}

TEST(KdTree3fMoves, EmptiedSubtreesAndUnrefittedSearches) {
  std::vector<float> xyz;
  for (int i = 0; i < 64; ++i) xyz.insert(xyz.end(), {float(i), 0.5f * float(i % 3), 0.0f});
  KdTree3f tree;
  tree.Build(xyz);
  for (int i = 0; i < 60; ++i) tree.Hide(i);  // whole leaves and subtrees empty
  const float q[3] = {10.0f, 0.0f, 0.0f};
  int idx[4];
  float sq[4];
  EXPECT_THROW(tree.Nearest(q, 2, idx, sq), InternalError);  // searched before Refit: refused
  tree.Refit();
  ASSERT_EQ(tree.Nearest(q, 4, idx, sq), 4);
  std::vector<int> got(idx, idx + 4);
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, (std::vector<int>{60, 61, 62, 63}));
  for (int i = 60; i < 64; ++i) tree.Hide(i);
  tree.Refit();
  EXPECT_EQ(tree.Nearest(q, 4, idx, sq), 0);
}

/// Points of a 6 x 5 x 2 m box shifted along x by `shift`, in float.
Cloud BoxPoints(RandomStream* rng, int n, float shift) {
  Cloud c;
  for (int i = 0; i < n; ++i) {
    pcl::PointXYZI p;
    p.x = float(rng->Uniform() * 6) + shift;
    p.y = float(rng->Uniform() * 5 - 2.5);
    p.z = float(rng->Uniform() * 2);
    p.intensity = float(rng->Uniform());
    c.push_back(p);
  }
  return c;
}

void ExpectExact(const CentroidIndex& index, const VoxelCentroidTable& table, RandomStream* rng, float x0) {
  Cloud centroids;
  table.Centroids(&centroids);
  ASSERT_EQ(index.size(), centroids.size());
  const int k = 6;
  int slots[CentroidIndex::kMaxK];
  float sq[CentroidIndex::kMaxK], xyz[3 * CentroidIndex::kMaxK];
  for (int trial = 0; trial < 150; ++trial) {
    const float q[3] = {x0 + float(rng->Uniform() * 8 - 1), float(rng->Uniform() * 7 - 3.5), float(rng->Uniform() * 3)};
    // Every other query bounded (as registration searches within a radius).
    const float bound = trial % 2 ? 0.04f : std::numeric_limits<float>::infinity();
    const int found = index.Nearest(q, k, slots, sq, bound, xyz);
    std::vector<float> brute;
    for (const auto& c : centroids) {
      const float p[3] = {c.x, c.y, c.z};
      if (SqDist(q, p) < bound) brute.push_back(SqDist(q, p));
    }
    std::sort(brute.begin(), brute.end());
    ASSERT_EQ(found, std::min<int>(k, int(brute.size())));
    for (int j = 0; j < found; ++j) {
      EXPECT_EQ(sq[j], brute[size_t(j)]);
      const pcl::PointXYZI c = table.MeanAt(size_t(slots[j])).point;
      EXPECT_TRUE(xyz[3 * j] == c.x && xyz[3 * j + 1] == c.y && xyz[3 * j + 2] == c.z);
      EXPECT_EQ(SqDist(q, xyz + 3 * j), sq[j]);
      EXPECT_TRUE(index.view(slots[j]) == table.MeanAt(size_t(slots[j])).view);
    }
  }
}

TEST(CentroidIndex, FollowsASlidingWindowExactlyThroughRebuildsAndCompaction) {
  RandomStream rng(4, "test.registration.centroid_index");
  VoxelCentroidTable table(0.2);
  CentroidIndex index;
  std::vector<Cloud> sets;
  constexpr int kWindow = 8;
  int layouts = 0;
  uint64_t last_layout = table.layout_version();
  for (int i = 0; i < 40; ++i) {
    const float shift = 0.35f * float(i);  // the window moves on: new voxels, dead voxels, compaction
    sets.push_back(BoxPoints(&rng, 3000, shift));
    table.Add(sets.back());
    if (i >= kWindow) table.Remove(sets[size_t(i - kWindow)]);
    index.Sync(&table);
    if (table.layout_version() != last_layout) ++layouts, last_layout = table.layout_version();
    SCOPED_TRACE("step " + std::to_string(i));
    ExpectExact(index, table, &rng, shift);
  }
  // The schedule this test is meant to cover: overflow between rebuilds, several rebuilds, compaction.
  EXPECT_GE(index.main_builds(), 3);
  EXPECT_LT(index.main_builds(), 30);
  EXPECT_GE(index.background_builds(), 2);  // exact also while a background build was pending and after its swap
  EXPECT_GE(layouts, 1);
  table.Clear();
  index.Sync(&table);
  EXPECT_EQ(index.size(), 0u);
  int slot;
  float sq;
  const float q[3] = {0, 0, 0};
  EXPECT_EQ(index.Nearest(q, 1, &slot, &sq), 0);
}

}  // namespace
}  // namespace rotolidar
