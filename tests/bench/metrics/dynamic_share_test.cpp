// The dynamic-object share of a map (bench/metrics/dynamic_share.hpp) on synthetic data with a known answer:
// the static scene is the plane z = 0; a walker's returns sit around (2, 0, 1) plus one at its foot.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "bench/metrics/dynamic_share.hpp"

namespace rotolidar::bench {
namespace {

std::vector<sim::DynamicHitSample> WalkerHits() {
  return {{0.10, 0, Eigen::Vector3d(2.025, 0.025, 1.025)},   // voxel A
          {0.11, 0, Eigen::Vector3d(2.035, 0.015, 1.030)},   // voxel A again
          {0.12, 0, Eigen::Vector3d(2.125, 0.025, 1.025)},   // voxel B
          {0.13, 1, Eigen::Vector3d(2.325, 0.025, 1.025)},   // voxel C (another object)
          {0.14, 0, Eigen::Vector3d(2.025, 0.025, 0.075)}};  // voxel D: the foot, 7.5 cm above the floor
}

std::vector<Eigen::Vector3f> Map() {
  return {{2.03f, 0.02f, 1.02f},   // dynamic: 0.6 cm from a hit in A
          {2.10f, 0.02f, 1.02f},   // dynamic: 2.6 cm from the hit in B
          {2.05f, 0.05f, 1.10f},   // dynamic: 8.3 cm from the first hit
          {2.03f, 0.02f, 0.01f},   // next to the foot's hit but 1 cm above the floor: static
          {0.00f, 0.00f, 0.01f},   // floor
          {1.00f, 0.00f, 0.00f},   // floor
          {3.00f, 1.00f, 0.02f},   // floor
          {2.50f, 0.00f, 1.00f}};  // off the floor, 18 cm from the nearest hit: not the walker
}

TEST(DynamicShare, CountsTheMapPointsOffTheStaticSurfaceNextToDynamicReturns) {
  int asked = 0;
  const StaticDistanceFn floor = [&asked](const Eigen::Vector3d& p, double) {
    ++asked;
    return std::abs(p.z());
  };
  DynamicShare share;
  const Status s = ComputeDynamicShare(WalkerHits(), Map(), floor, DynamicShareConfig{}, &share);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(share.returns_seen, 5u);
  EXPECT_EQ(share.voxels_seen, 4u);
  EXPECT_EQ(share.map_points, 8u);
  EXPECT_EQ(share.map_points_dynamic, 3u);
  EXPECT_EQ(share.voxels_reached, 2u);  // two points' nearest return is in A, one's in B
  EXPECT_DOUBLE_EQ(share.share_of_seen, 2.0 / 4.0);
  EXPECT_DOUBLE_EQ(share.share_of_map, 3.0 / 8.0);
  EXPECT_EQ(asked, 4);  // only the points within hit_radius_m of a return
  // Per object: object 0 (A, B, D) kept its three points in A and B; object 1 (C) nothing.
  ASSERT_EQ(share.per_object.size(), 2u);
  EXPECT_EQ(share.per_object[0].returns_seen, 4u);
  EXPECT_EQ(share.per_object[0].voxels_seen, 3u);
  EXPECT_EQ(share.per_object[0].map_points_dynamic, 3u);
  EXPECT_EQ(share.per_object[0].voxels_reached, 2u);
  EXPECT_DOUBLE_EQ(share.per_object[0].share_of_seen, 2.0 / 3.0);
  EXPECT_EQ(share.per_object[1].object_id, 1);
  EXPECT_EQ(share.per_object[1].returns_seen, 1u);
  EXPECT_EQ(share.per_object[1].voxels_seen, 1u);
  EXPECT_EQ(share.per_object[1].map_points_dynamic, 0u);
  EXPECT_DOUBLE_EQ(share.per_object[1].share_of_seen, 0.0);
  share.per_object[0].name = "walker";
  EXPECT_EQ(DynamicObjectLines(share),
            "  walker (id 0): 4 returns, 3 voxels; the map reached 2 (66.67 %) with 3 points\n"
            "  object (id 1): 1 returns, 1 voxels; the map reached 0 (0.00 %) with 0 points\n");
  EXPECT_EQ(DynamicShareLine(share),
            "dynamic objects: 5 returns seen in 4 voxels; the dense map reached 2 of those voxels (50.00 %) with 3 "
            "points (37.50 % of the map)");
}

TEST(DynamicShare, ThresholdsAndVoxelComeFromTheConfig) {
  const StaticDistanceFn floor = [](const Eigen::Vector3d& p, double) { return std::abs(p.z()); };
  DynamicShareConfig wide;
  wide.hit_radius_m = 0.2;        // now the point 18 cm away counts too
  wide.static_clearance_m = 0.005;  // and so does the one 1 cm above the floor
  wide.voxel_m = 1.0;             // every hit in voxel (2, 0, 1) or (2, 0, 0)
  DynamicShare share;
  ASSERT_TRUE(ComputeDynamicShare(WalkerHits(), Map(), floor, wide, &share).ok);
  EXPECT_EQ(share.voxels_seen, 2u);
  EXPECT_EQ(share.map_points_dynamic, 5u);
  EXPECT_EQ(share.voxels_reached, 2u);  // the body's voxel and the foot's
  EXPECT_DOUBLE_EQ(share.share_of_seen, 1.0);
  nlohmann::json j;
  ToJson(share, wide, &j);
  EXPECT_EQ(j.at("map_points_dynamic").get<size_t>(), 5u);
  EXPECT_EQ(j.at("returns_seen").get<size_t>(), 5u);
  EXPECT_EQ(j.at("hit_radius_m").get<double>(), 0.2);
  EXPECT_EQ(j.at("static_clearance_m").get<double>(), 0.005);
  EXPECT_EQ(j.at("voxel_m").get<double>(), 1.0);
  for (const char* key : {"voxels_seen", "voxels_reached", "map_points", "share_of_seen", "share_of_map"}) EXPECT_TRUE(j.contains(key));
  ASSERT_EQ(j.at("per_object").size(), 2u);
  EXPECT_EQ(j.at("per_object")[1].at("object_id").get<int>(), 1);
  EXPECT_EQ(j.at("per_object")[1].at("voxels_reached").get<size_t>(), 1u);  // C's voxel, by the 18 cm point
}

TEST(DynamicShare, NothingSeenGivesZeroSharesAndBadConfigsNameTheField) {
  const StaticDistanceFn never = [](const Eigen::Vector3d&, double) -> double {
    ADD_FAILURE() << "asked without hits";
    return 1.0;
  };
  DynamicShare share;
  ASSERT_TRUE(ComputeDynamicShare({}, Map(), never, DynamicShareConfig{}, &share).ok);
  EXPECT_EQ(share.returns_seen, 0u);
  EXPECT_EQ(share.voxels_seen, 0u);
  EXPECT_EQ(share.map_points, 8u);
  EXPECT_EQ(share.map_points_dynamic, 0u);
  EXPECT_EQ(share.share_of_seen, 0.0);
  EXPECT_EQ(share.share_of_map, 0.0);
  ASSERT_TRUE(ComputeDynamicShare(WalkerHits(), {}, never, DynamicShareConfig{}, &share).ok);
  EXPECT_EQ(share.map_points_dynamic, 0u);
  EXPECT_EQ(share.share_of_map, 0.0);

  DynamicShareConfig bad;
  bad.hit_radius_m = 0.0;
  Status s = ComputeDynamicShare(WalkerHits(), Map(), never, bad, &share);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("hit_radius_m"), std::string::npos) << s.message;
  s = ComputeDynamicShare(WalkerHits(), Map(), nullptr, DynamicShareConfig{}, &share);
  EXPECT_FALSE(s.ok);
}

}  // namespace
}  // namespace rotolidar::bench
