// Embree ray casting: closed rooms do not leak, distances and normals match analytic geometry, the batched and
// single-ray calls agree, concurrent calls are safe, bad meshes are refused.
#include <thread>

#include <gtest/gtest.h>

#include "core/util/rng.hpp"
#include "sim/world/embree_scene.hpp"
#include "tests/sim/world_fixtures.hpp"

namespace rotolidar::sim {
namespace {

Eigen::Vector3d RandomUnit(RandomStream* rng) {
  const Eigen::Vector3d v(rng->Normal(), rng->Normal(), rng->Normal());
  return v.normalized();
}

Eigen::Vector3d RandomInside(const Eigen::AlignedBox3d& box, double margin_m, RandomStream* rng) {
  const Eigen::Vector3d lo = box.min().array() + margin_m, hi = box.max().array() - margin_m;
  return lo + (hi - lo).cwiseProduct(Eigen::Vector3d(rng->Uniform(), rng->Uniform(), rng->Uniform()));
}

TEST(EmbreeScene, RaysFromInsideClosedRoomNeverEscape) {
  Scene scene;
  ASSERT_TRUE(LoadScene(testing::BoxRoomPath(), &scene).ok);
  ASSERT_TRUE(scene.closed);
  const auto es = testing::MakeEmbree(scene);
  RandomStream rng(7, "test.rays");
  const double diagonal_m = scene.bounds.diagonal().norm();
  std::vector<RayQuery> queries;
  for (int i = 0; i < 5000; ++i) {
    queries.push_back({RandomInside(scene.bounds, 0.02, &rng), RandomUnit(&rng), 1e3});
  }
  std::vector<RayHit> batch(queries.size());
  es->IntersectBatch(queries.data(), queries.size(), batch.data());
  for (size_t i = 0; i < queries.size(); ++i) {
    const RayHit hit = es->Intersect(queries[i].origin_world, queries[i].dir_world, 1e3);
    ASSERT_TRUE(hit.hit) << "ray " << i << " escaped";
    EXPECT_LE(hit.distance_m, diagonal_m + 1e-6);
    EXPECT_LE(hit.normal_world.dot(queries[i].dir_world), 0.0);
    EXPECT_NEAR(hit.normal_world.norm(), 1.0, 1e-12);
    // The stream API traverses the same structure: same triangle, same distance.
    EXPECT_TRUE(batch[i].hit);
    EXPECT_EQ(batch[i].triangle_id, hit.triangle_id);
    EXPECT_EQ(batch[i].distance_m, hit.distance_m);
  }
}

TEST(EmbreeScene, HitsWallsAtAnalyticDistance) {
  const Scene scene = testing::PlainRoom();
  const auto es = testing::MakeEmbree(scene);
  const Eigen::Vector3d o(1.0, 0.3, 1.2);
  RayHit hit = es->Intersect(o, Eigen::Vector3d::UnitX(), 100.0);
  ASSERT_TRUE(hit.hit);
  // Float vertices and rays: ~1e-6 relative, so 1e-5 m at these distances.
  EXPECT_NEAR(hit.distance_m, 4.0, 1e-5);
  EXPECT_TRUE(hit.normal_world.isApprox(-Eigen::Vector3d::UnitX(), 1e-9));
  EXPECT_TRUE(hit.front_face);
  EXPECT_EQ(hit.material_id, 0);

  hit = es->Intersect(o, -Eigen::Vector3d::UnitZ() * 3.0, 100.0);  // non-unit direction is normalised
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.distance_m, 1.2, 1e-5);
  EXPECT_EQ(hit.material_id, 1);

  const Eigen::Vector3d d = Eigen::Vector3d(1.0, 0.6, 0.2).normalized();  // reaches x = 5 at y = 2.7, z = 2.1
  hit = es->Intersect(o, d, 100.0);
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.distance_m, 4.0 / d.x(), 1e-5);
  EXPECT_NEAR(-hit.normal_world.dot(d), d.x(), 1e-9);  // cos(incidence)

  EXPECT_FALSE(es->Intersect(o, Eigen::Vector3d::UnitX(), 3.9).hit);  // t_max before the wall
  EXPECT_FALSE(es->Intersect(o, Eigen::Vector3d::Zero(), 100.0).hit);
}

TEST(EmbreeScene, BackFacesAreHitAndReported) {
  const auto es = testing::MakeEmbree(testing::PlainRoom());
  const RayHit hit = es->Intersect(Eigen::Vector3d(8, 0, 1), -Eigen::Vector3d::UnitX(), 100.0);
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.distance_m, 3.0, 1e-5);
  EXPECT_FALSE(hit.front_face);  // the outside of an inward wall
  EXPECT_TRUE(hit.normal_world.isApprox(Eigen::Vector3d::UnitX(), 1e-9));
}

TEST(EmbreeScene, ConcurrentCallsMatchSerial) {
  Scene scene;
  ASSERT_TRUE(LoadScene(testing::BoxRoomPath(), &scene).ok);
  const auto es = testing::MakeEmbree(scene);
  RandomStream rng(3, "test.rays");
  std::vector<RayQuery> q;
  for (int i = 0; i < 2000; ++i) q.push_back({RandomInside(scene.bounds, 0.1, &rng), RandomUnit(&rng), 50.0});
  std::vector<RayHit> serial(q.size()), a(q.size()), b(q.size());
  for (size_t i = 0; i < q.size(); ++i) serial[i] = es->Intersect(q[i].origin_world, q[i].dir_world, 50.0);
  std::thread ta([&] {
    for (size_t i = 0; i < q.size(); ++i) a[i] = es->Intersect(q[i].origin_world, q[i].dir_world, 50.0);
  });
  std::thread tb([&] { es->IntersectBatch(q.data(), q.size(), b.data()); });
  ta.join();
  tb.join();
  for (size_t i = 0; i < q.size(); ++i) {
    EXPECT_EQ(a[i].triangle_id, serial[i].triangle_id);
    EXPECT_EQ(b[i].distance_m, serial[i].distance_m);
  }
}

TEST(EmbreeScene, RefusesBadMeshes) {
  std::unique_ptr<EmbreeScene> es;
  TriangleMesh empty;
  EXPECT_FALSE(EmbreeScene::Create(empty, &es).ok);

  TriangleMesh mesh = BuildMesh(testing::PlainRoom());
  mesh.triangles[5] = Eigen::Vector3i(0, 1, 999);
  Status s = EmbreeScene::Create(mesh, &es);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("triangle 5"), std::string::npos) << s.message;

  mesh = BuildMesh(testing::PlainRoom());
  mesh.material_ids[3] = 7;
  s = EmbreeScene::Create(mesh, &es);
  EXPECT_NE(s.message.find("triangle 3"), std::string::npos) << s.message;

  mesh = BuildMesh(testing::PlainRoom());
  mesh.triangles[2] = Eigen::Vector3i(0, 0, 1);
  s = EmbreeScene::Create(mesh, &es);
  EXPECT_NE(s.message.find("degenerate"), std::string::npos) << s.message;
  EXPECT_EQ(es, nullptr);
}

}  // namespace
}  // namespace rotolidar::sim
