// Point-to-mesh distance (bench/metrics/surface_distance.hpp): the exact point-triangle distance against a dense
// search, and the BVH search against a brute-force search over every triangle of a shipped scene.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <string>

#include "bench/metrics/surface_distance.hpp"
#include "core/util/rng.hpp"

namespace rotolidar::bench {
namespace {

TEST(SurfaceDistance, ClosestPointOnTriangleMatchesADenseSearch) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0.2), c(0.3, 0.8, -0.1);
  RandomStream rng(3, "closest_point_test");
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p{3 * rng.Uniform() - 1, 3 * rng.Uniform() - 1, 2 * rng.Uniform() - 1};
    double best = 1e9;
    for (int u = 0; u <= 400; ++u)  // barycentric grid with step 1/400: error < edge / 400 < 3 mm
      for (int v = 0; u + v <= 400; ++v)
        best = std::min(best, (a + (b - a) * (u / 400.0) + (c - a) * (v / 400.0) - p).norm());
    const double exact = (ClosestPointOnTriangle(p, a, b, c) - p).norm();
    EXPECT_LE(exact, best + 1e-12);
    EXPECT_GT(exact, best - 3e-3);
  }
}

/// The smallest ClosestPointOnTriangle distance over every triangle of `mesh`.
double BruteForceDistance(const sim::TriangleMesh& mesh, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const auto& v = mesh.vertices_m;
    best = std::min(best, (ClosestPointOnTriangle(p, v[t[0]], v[t[1]], v[t[2]]) - p).norm());
  }
  return best;
}

TEST(SurfaceDistance, MatchesABruteForceSearchOverEveryTriangle) {
  sim::Scene scene;
  ASSERT_TRUE(sim::LoadScene(std::string(ROTOLIDAR_SOURCE_DIR) + "/scenes/lab.yaml", &scene).ok);
  const sim::TriangleMesh mesh = sim::BuildMesh(scene);
  std::unique_ptr<SurfaceDistance> surface;
  ASSERT_TRUE(SurfaceDistance::Create(mesh, &surface).ok);
  RandomStream rng(5, "surface_distance_test");
  const Eigen::Vector3d lo = scene.bounds.min().array() - 1.0, hi = scene.bounds.max().array() + 1.0;
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3d u{rng.Uniform(), rng.Uniform(), rng.Uniform()};
    const Eigen::Vector3d p = lo + (hi - lo).cwiseProduct(u);
    const double expected = BruteForceDistance(mesh, p);
    int id = -1;
    const double d = surface->Distance(p, 1e3, &id);
    // The search radius is a float: a candidate within ~1e-7 relative of the best may be pruned.
    ASSERT_NEAR(d, expected, 1e-6 * std::max(1.0, expected)) << "point " << i;
    ASSERT_GE(id, 0);
    const Eigen::Vector3i& t = mesh.triangles[static_cast<size_t>(id)];
    const auto& v = mesh.vertices_m;
    EXPECT_DOUBLE_EQ((ClosestPointOnTriangle(p, v[t[0]], v[t[1]], v[t[2]]) - p).norm(), d);  // the id is the nearest
    // Nothing within a radius below the distance: the radius comes back, with no triangle.
    if (expected > 0.01) {
      int none = 7;
      EXPECT_EQ(surface->Distance(p, 0.5 * expected, &none), 0.5 * expected);
      EXPECT_EQ(none, -1);
    }
  }
}

TEST(SurfaceDistance, RefusesAnEmptyMesh) {
  std::unique_ptr<SurfaceDistance> surface;
  const Status s = SurfaceDistance::Create(sim::TriangleMesh{}, &surface);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("no triangles"), std::string::npos) << s.message;
}

}  // namespace
}  // namespace rotolidar::bench
