// MapRecheck (core/pipeline/map_recheck.hpp): dense-map points whose spot later scans see through, in a row,
// leave the map; the room stays, a hit resets the count, and far or old points are left alone.
#include <gtest/gtest.h>

#include <vector>

#include "core/pipeline/free_space.hpp"
#include "core/pipeline/map_recheck.hpp"
#include "core/pipeline/voxel_map.hpp"
#include "tests/core/pipeline/room_scans.hpp"

namespace rotolidar {
namespace {

using test::OnBall;
using test::Scan;

const Eigen::Vector3d kA(3.0, 1.0, 0.0), kB(-2.0, -2.5, 0.5);

/// A dense map holding the room and the ball at A (as if the ball had stood there for longer than the delayed
/// test's window), all tracked by `recheck` at t = 0.
std::vector<size_t> MapWithBallAtA(VoxelMap* map, MapRecheck* recheck) {
  std::vector<Eigen::Vector3d> points;
  for (const ScanPoint& p : Scan(kA)) points.push_back(p.p_base.cast<double>());
  std::vector<size_t> kept;
  map->Add(points.data(), points.size(), &kept);
  recheck->Track(0.0, *map, kept);
  return kept;
}

size_t CountOnBall(const VoxelMap& map, const Eigen::Vector3d& c) {
  size_t n = 0;
  for (const Eigen::Vector3d& p : map.Points()) n += OnBall(p, c) ? 1 : 0;
  return n;
}

/// Scans at t = 0.1 k (k = 1..n) with the ball where `ball_at(k)` says; each votes, and what it finds leaves the map.
template <class BallAt>
size_t RunScans(const FreeSpaceConfig& config, int n, BallAt&& ball_at, VoxelMap* map, MapRecheck* recheck) {
  FreeSpaceFilter filter(config, Eigen::Vector3d::Zero());
  size_t removed = 0;
  for (int k = 1; k <= n; ++k) {
    filter.AddScan(0.1 * k, Pose3::Identity(), Scan(ball_at(k)), 40.0);
    std::vector<size_t> remove;
    recheck->Vote(0.1 * k, filter.Newest(), &remove);
    for (size_t index : remove) removed += map->Remove(index) ? 1 : 0;
  }
  return removed;
}

TEST(MapRecheck, TakesTheLeftBallOutKeepsTheRoom) {
  const FreeSpaceConfig config;  // two looks in a row, every other scan votes
  VoxelMap map(0.05, 1);
  MapRecheck recheck(config);
  const std::vector<size_t> kept = MapWithBallAtA(&map, &recheck);
  const size_t on_a = CountOnBall(map, kA), all = map.NumPoints();
  ASSERT_GT(on_a, 100u);
  EXPECT_EQ(recheck.tracked(), kept.size());
  // The ball moved to B: scans 1 and 3 vote, and both see through A.
  const size_t removed = RunScans(config, 4, [](int) { return kB; }, &map, &recheck);
  EXPECT_EQ(CountOnBall(map, kA), 0u) << "of " << on_a;
  EXPECT_EQ(map.NumPoints(), all - removed);
  // Of the room at most the sliver around the ball's outline whose 3x3 neighbourhood straddles ball and wall.
  EXPECT_LT(removed - on_a, (all - on_a) / 1000) << "room points removed";
  // A removed voxel takes a point again (one point per voxel: the spot is free).
  std::vector<size_t> again;
  const Eigen::Vector3d near_a = kA - 0.3 * kA.normalized();
  map.Add(&near_a, 1, &again);
  EXPECT_EQ(again.size(), 1u);
}

TEST(MapRecheck, AHitBetweenLooksKeepsThePoint) {
  FreeSpaceConfig config;
  config.vote_every_scans = 1;
  VoxelMap map(0.05, 1);
  MapRecheck recheck(config);
  MapWithBallAtA(&map, &recheck);
  const size_t on_a = CountOnBall(map, kA);
  // The ball comes back every other scan: never two looks through A in a row.
  RunScans(config, 8, [](int k) { return k % 2 == 0 ? kA : kB; }, &map, &recheck);
  EXPECT_EQ(CountOnBall(map, kA), on_a);
}

TEST(MapRecheck, LeavesFarAndOldPointsAlone) {
  FreeSpaceConfig config;
  config.recheck_max_range_m = 2.5;  // the ball at A is 3.2 m from the sensor
  VoxelMap map(0.05, 1);
  MapRecheck far(config);
  MapWithBallAtA(&map, &far);
  const size_t on_a = CountOnBall(map, kA);
  RunScans(config, 4, [](int) { return kB; }, &map, &far);
  EXPECT_EQ(CountOnBall(map, kA), on_a);
  // Tracked for longer than recheck_s: forgotten, not judged.
  config = FreeSpaceConfig();
  config.recheck_s = 0.15;
  VoxelMap map2(0.05, 1);
  MapRecheck old(config);
  MapWithBallAtA(&map2, &old);
  RunScans(config, 4, [](int) { return kB; }, &map2, &old);
  EXPECT_EQ(CountOnBall(map2, kA), on_a);  // scan 1 saw through A once; scan 3 came after the points were gone
  EXPECT_EQ(old.tracked(), 0u);
}

TEST(FreeSpaceConfig, RecheckKeysAreValidated) {
  FreeSpaceConfig c;
  std::string why;
  c.recheck_min_through = 0;
  EXPECT_FALSE(c.Validate(&why));
  EXPECT_NE(why.find("recheck_min_through"), std::string::npos);
  c = FreeSpaceConfig();
  c.recheck_max_range_m = 0.0;
  EXPECT_FALSE(c.Validate(&why));
  EXPECT_NE(why.find("recheck_max_range_m"), std::string::npos);
  c = FreeSpaceConfig();
  c.recheck_s = -1.0;
  EXPECT_FALSE(c.Validate(&why));
  EXPECT_NE(why.find("recheck_s"), std::string::npos);
}

}  // namespace
}  // namespace rotolidar
