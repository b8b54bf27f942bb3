// The edge noise gate on oblique surfaces (FeatureConfig::range_sigma_incidence_exponent): a VLP-16 revolution in
// a corridor whose range noise grows as 1 / cos(incidence), as a real beam's footprint does on an oblique wall.
// With one sigma for every point the noise on the long side walls passes the gate as edges; with the incidence-
// aware gate it does not, and the corridor's real corners are still found.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/features/curvature_features.hpp"
#include "core/util/rng.hpp"
#include "core/wire/vlp16.hpp"
#include "tests/core/features/feature_test_util.hpp"

namespace rotolidar {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

struct Room {
  double lo[3], hi[3];  ///< an axis-aligned box around the origin [m]
};
// A corridor 2.5 m wide, 62 m long: its side walls are seen ever more obliquely. Floor and ceiling lie beyond the
// rings' reach here and in the room below.
constexpr Room kCorridor{{-2.0, -1.0, -40.0}, {60.0, 1.5, 40.0}};
// A 10 m x 8 m room: its four vertical corners are seen at 5-8 m, each face at 30-60 deg incidence.
constexpr Room kRoom{{-6.0, -5.0, -10.0}, {4.0, 3.0, 10.0}};

// One revolution from the origin at 600 rpm; range noise sigma0 / max(cos(incidence), 0.5), the twin's typical
// growth (docs/noise_models.md).
std::vector<ScanPoint> Cast(const Room& room, double sigma0_m, uint64_t seed) {
  RandomStream rng(seed, "incidence_gate_test.range_noise");
  std::vector<ScanPoint> pts;
  for (int k = 0; k < 1800; ++k) {
    const double az_deg = 0.2 * k;
    for (int ring = 0; ring < 16; ++ring) {
      const Eigen::Vector3d d = Vlp16RayDirection((-15.0 + 2.0 * ring) * kDeg, az_deg * kDeg);
      double t = std::numeric_limits<double>::infinity();
      int axis = 0;
      for (int a = 0; a < 3; ++a) {
        const double ta = d[a] > 1e-12 ? room.hi[a] / d[a] : (d[a] < -1e-12 ? room.lo[a] / d[a] : t);
        if (ta < t) t = ta, axis = a;
      }
      const double cos_incidence = std::abs(d[axis]);  // the hit wall's normal is that axis
      const double r = t + sigma0_m / std::max(cos_incidence, 0.5) * rng.Normal();
      pts.push_back(test::SyntheticReturn(d, r, az_deg, ring, k));
    }
  }
  return pts;
}

struct EdgeCounts {
  int at_corners = 0, elsewhere = 0;
};

EdgeCounts CountEdges(const Room& room, const std::vector<ScanPoint>& pts, double exponent) {
  FeatureConfig config = test::SeedFeatureConfig();
  config.range_sigma_m = 0.02;
  config.range_sigma_incidence_exponent = exponent;
  const FeatureResult r = ExtractFeatures(pts, 0.0, config);
  EdgeCounts n;
  for (const auto& p : r.features.edge) {
    double to_corner = std::numeric_limits<double>::infinity();
    for (const double x : {room.lo[0], room.hi[0]})
      for (const double y : {room.lo[1], room.hi[1]}) to_corner = std::min(to_corner, std::hypot(p.x - x, p.y - y));
    ++(to_corner < 0.1 ? n.at_corners : n.elsewhere);
  }
  return n;
}

TEST(IncidenceGate, NoiseOnObliqueWallsIsNoEdge) {
  for (const Room* room_ptr : {&kCorridor, &kRoom}) {
    const Room& room = *room_ptr;
    EdgeCounts flat, grown;
    for (const uint64_t seed : {1, 2, 3}) {
      const std::vector<ScanPoint> pts = Cast(room, 0.02, seed);
      const EdgeCounts a = CountEdges(room, pts, 0.0), b = CountEdges(room, pts, 1.0);
      flat.at_corners += a.at_corners, flat.elsewhere += a.elsewhere;
      grown.at_corners += b.at_corners, grown.elsewhere += b.elsewhere;
    }
    std::printf("[measured] edges at the corners / elsewhere over 3 seeds: one sigma %d / %d, grown %d / %d\n",
                flat.at_corners, flat.elsewhere, grown.at_corners, grown.elsewhere);
    // Measured: corridor 53 / 1278 -> 0 / 2, room 163 / 838 -> 66 / 75 (of 192 corner rays). A 3-sigma gate
    // that knew every point's sigma would pass ~0.27 % of the 28,800 points, ~78 per seed: the grown gate
    // stays below that (0-25 per seed), the flat one is 3.5-5.5x above it (280-430). The corners' faces lie at
    // 30-60 deg, their returns 1.15-2x noisier: the corners left out are those within 3 grown sigmas, which the
    // flat gate drops at that noise too.
    EXPECT_GT(flat.elsewhere, 8 * std::max(1, grown.elsewhere));
    if (&room == &kRoom) {
      EXPECT_GE(3 * grown.at_corners, flat.at_corners);
    }
  }
}

TEST(IncidenceGate, ValidateNamesTheFields) {
  FeatureConfig c;
  std::string why;
  c.range_sigma_incidence_exponent = -1.0;
  EXPECT_FALSE(c.Validate(&why));
  EXPECT_NE(why.find("features.range_sigma_incidence_exponent"), std::string::npos) << why;
  c = FeatureConfig();
  c.range_sigma_min_cos = 0.0;
  EXPECT_FALSE(c.Validate(&why));
  EXPECT_NE(why.find("features.range_sigma_min_cos"), std::string::npos) << why;
}

}  // namespace
}  // namespace rotolidar
