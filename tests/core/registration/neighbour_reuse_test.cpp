// ScanToMapConfig::neighbour_reuse_m: neighbour sets kept across outer iterations while a point moves less than
// the reuse distance. Exact reuse (0) and approximate reuse must land on the same pose; approximate reuse must
// search the map less; the count of searches must be what the result reports.
#include <cmath>

#include <gtest/gtest.h>

#include "core/registration/scan_to_map.hpp"
#include "core/util/rng.hpp"
#include "tests/core/registration/feature_scenes.hpp"

namespace rotolidar {
namespace {

using namespace feature_scenes;  // NOLINT: the shared synthetic scenes

struct Case {
  ScanToMapResult exact, reused;
  size_t features = 0;
};

Case RegisterBothWays(const Vector6d& offset, double reuse_m) {
  RandomStream rng(11, "test.registration.neighbour_reuse");
  const Scene scene = BoxRoom();
  const LocalMap map = MapOf(scene, rng);
  const FeatureSet scan = Sample(scene, 4.0, 5.0, 0.01, kTruth, rng);
  ScanToMapConfig config;
  config.neighbour_reuse_m = 0.0;  // exact: a set is reused only while provably still the k nearest
  Case c;
  c.features = scan.edge.size() + scan.planar.size();
  c.exact = Register(scan, map, PoseBoxPlus(kTruth, offset), config);
  config.neighbour_reuse_m = reuse_m;
  c.reused = Register(scan, map, PoseBoxPlus(kTruth, offset), config);
  return c;
}

TEST(NeighbourReuse, LandsWhereExactReuseDoesWithFewerSearches) {
  Vector6d offset;
  offset << 0.04, -0.03, 0.02, 0.004, -0.003, 0.01;  // an IMU-prediction-sized error: 5 cm, 0.7 deg
  const Case c = RegisterBothWays(offset, 0.05);
  ASSERT_TRUE(c.exact.converged) << c.exact.message;
  ASSERT_TRUE(c.reused.converged) << c.reused.message;
  const Vector6d d = PoseBoxMinus(c.reused.T_map_scan, c.exact.T_map_scan);
  const double exact_m = (c.exact.T_map_scan.translation() - kTruth.translation()).norm();
  const double reused_m = (c.reused.T_map_scan.translation() - kTruth.translation()).norm();
  std::printf("exact: %d searches, %d rebuilds, %.2e m / %.2e rad from truth; reuse 5 cm: %d searches, %d "
              "rebuilds, %.2e m / %.2e rad; apart %.2e m %.2e rad\n",
              c.exact.neighbour_searches, c.exact.iterations, exact_m, RotationErrorRad(c.exact.T_map_scan, kTruth),
              c.reused.neighbour_searches, c.reused.iterations, reused_m,
              RotationErrorRad(c.reused.T_map_scan, kTruth), d.head<3>().norm(), d.tail<3>().norm());
  // Every feature is searched at least once; exact reuse re-searched most points after the first rebuild.
  EXPECT_GE(c.exact.neighbour_searches, int(c.features));
  EXPECT_GE(c.reused.neighbour_searches, int(c.features));
  EXPECT_LT(c.reused.neighbour_searches, c.exact.neighbour_searches);
  // Measured: exact 0.93 mm / 0.27 mrad from the truth (1 cm point noise), reuse 0.52 mm / 0.32 mrad, 0.71 mm /
  // 0.13 mrad apart: the sets found within 5 cm fit the same planes and lines, to the registration's own noise.
  // Bounds ~3x the measured gap; a wrong reuse (stale sets after a real move) gives centimetres.
  EXPECT_LT(d.head<3>().norm(), 2e-3);
  EXPECT_LT(d.tail<3>().norm(), 5e-4);
  EXPECT_LT(reused_m, 0.005);
  EXPECT_LT(RotationErrorRad(c.reused.T_map_scan, kTruth), 0.05 * M_PI / 180.0);
}

TEST(NeighbourReuse, AFarGuessIsSearchedAgainAsItMoves) {
  Vector6d offset;
  offset << 0.3, -0.25, 0.15, 0.03, -0.04, 0.09;  // 0.43 m and ~6 deg: the first update moves every point > 5 cm
  const Case c = RegisterBothWays(offset, 0.05);
  ASSERT_TRUE(c.reused.converged) << c.reused.message;
  EXPECT_GE(c.reused.neighbour_searches, 2 * int(c.features));
  EXPECT_LT((c.reused.T_map_scan.translation() - kTruth.translation()).norm(), 0.005);
  EXPECT_LT(RotationErrorRad(c.reused.T_map_scan, kTruth), 0.05 * M_PI / 180.0);
}

TEST(NeighbourReuse, ValidateRejectsANegativeDistance) {
  ScanToMapConfig c;
  c.neighbour_reuse_m = -0.01;
  std::string error;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("scan_to_map.neighbour_reuse_m"), std::string::npos) << error;
}

}  // namespace
}  // namespace rotolidar
