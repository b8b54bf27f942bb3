// The thin-wall case of plane matching: a scan seeing the back face of a 15 cm wall whose front face is in the
// map must not match the front face's plane (registration.visibility_check), and the map's mean view vectors
// are removed exactly with their keyframe.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/registration/scan_to_map.hpp"
#include "tests/core/registration/room_points.hpp"
#include "core/registration/voxel_centroids.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZI>;

Pose3 At(const Eigen::Vector3d& t) { return MakePose(t, Eigen::Quaterniond::Identity()); }

TEST(Visibility, BackFaceOfAThinWallDoesNotMatchItsFrontFace) {
  RandomStream rng(3, "test.registration.visibility");
  const Eigen::Vector3d left(-3, 0, 1.5), right(3, 0, 1.5);
  // Keyframe on the left: room x in [-5, 0] with the wall's front face at x = 0. Keyframe on the right: room
  // x in [0.15, 5] with its end wall, but not yet the wall's back face at x = 0.15 (as when first through a door).
  std::vector<Eigen::Vector3d> seen_left, seen_right, scan;
  AddShell(-5, 0, rng, &seen_left);
  AddFace(0, -5.0, {-5, -2, 0}, {-5, 2, 3}, rng, &seen_left);
  AddFace(0, 0.0, {0, -2, 0}, {0, 2, 3}, rng, &seen_left);
  AddShell(0.15, 5, rng, &seen_right);
  AddFace(0, 5.0, {5, -2, 0}, {5, 2, 3}, rng, &seen_right);
  LocalMapConfig map_config;
  map_config.planar_voxel_m = 0.1;
  LocalMap map(map_config);
  map.AddKeyframe(InFrameOf(seen_left, left), At(left));
  map.AddKeyframe(InFrameOf(seen_right, right), At(right));
  // The scan from the right: the back face, the end wall and the shell.
  AddShell(0.15, 5, rng, &scan);
  AddFace(0, 5.0, {5, -2, 0}, {5, 2, 3}, rng, &scan);
  AddFace(0, 0.15, {0.15, -2, 0}, {0.15, 2, 3}, rng, &scan);
  const FeatureSet features = InFrameOf(scan, right);

  ScanToMapConfig config;
  const ScanToMapResult with = Register(features, map, At(right), config);
  config.visibility_check = false;
  const ScanToMapResult without = Register(features, map, At(right), config);
  ASSERT_TRUE(with.converged) << with.message;
  // Measured: with the check 5.1 mm from the truth along x (back-face points at the corners still mix with the
  // shell's planes); without it the back face (~1200 points) pulls the scan 71 mm toward the front face's plane.
  EXPECT_LT(std::abs(with.T_map_scan.translation().x() - right.x()), 0.01);
  EXPECT_GT(std::abs(without.T_map_scan.translation().x() - right.x()), 0.035);
  EXPECT_GT(without.planar_inliers, with.planar_inliers);  // the back face matched only without the check
}

TEST(Visibility, MeanViewsFollowTheSensorAndLeaveExactlyWithTheirPoints) {
  Cloud a, b;
  for (int i = 0; i < 50; ++i) {
    pcl::PointXYZI p;
    p.x = 0.01f * float(i);
    p.y = 0.0f;
    p.z = 0.0f;
    p.intensity = 0.0f;
    a.push_back(p);
    p.y = 0.003f;  // same voxels, seen from the other side
    b.push_back(p);
  }
  VoxelCentroidTable table(0.1);
  table.Add(a, Eigen::Vector3f(0.2f, 5.0f, 0.0f));
  std::vector<Eigen::Vector3f> only_a;
  table.MeanViews(&only_a);
  ASSERT_EQ(only_a.size(), 5u);
  for (const auto& v : only_a) EXPECT_GT(v.y(), 0.95f);  // seen from +y
  table.Add(b, Eigen::Vector3f(0.2f, -5.0f, 0.0f));
  std::vector<Eigen::Vector3f> both;
  table.MeanViews(&both);
  for (const auto& v : both) EXPECT_LT(std::abs(v.y()), 0.05f);  // both sides merged: ~0
  table.Remove(b, Eigen::Vector3f(0.2f, -5.0f, 0.0f));
  std::vector<Eigen::Vector3f> again;
  table.MeanViews(&again);
  ASSERT_EQ(again.size(), only_a.size());
  for (size_t i = 0; i < again.size(); ++i) EXPECT_EQ(again[i], only_a[i]) << i;  // bit-exact removal
}

}  // namespace
}  // namespace rotolidar
