// Embree ray casting: closed rooms do not leak, distances and normals match analytic geometry, the batched and
// single-ray calls agree, concurrent calls are safe, bad meshes are refused, dynamic objects move with SetTime;
// the point query offers the static triangles near a point.
#include <set>
#include <thread>

#include <gtest/gtest.h>

#include "core/util/rng.hpp"
#include "sim/world/scene_dynamic.hpp"
#include "sim/world/embree_scene.hpp"
#include "tests/sim/world/world_fixtures.hpp"

namespace rotolidar::sim {
namespace {

Eigen::Vector3d RandomUnit(RandomStream* rng) {
  const Eigen::Vector3d v{rng->Normal(), rng->Normal(), rng->Normal()};
  return v.normalized();
}

Eigen::Vector3d RandomInside(const Eigen::AlignedBox3d& box, double margin_m, RandomStream* rng) {
  const Eigen::Vector3d lo = box.min().array() + margin_m, hi = box.max().array() - margin_m;
  return lo + (hi - lo).cwiseProduct(Eigen::Vector3d{rng->Uniform(), rng->Uniform(), rng->Uniform()});
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

TEST(EmbreeScene, DynamicObjectsMoveWithSetTime) {
  const Scene scene = testing::RoomWithCar();
  std::unique_ptr<EmbreeScene> es;
  ASSERT_TRUE(EmbreeScene::Create(scene, &es).ok);
  ASSERT_EQ(es->num_dynamic_objects(), 1u);
  EXPECT_EQ(es->num_triangles(), 12u + 12u);
  // t = 1 s: the car (2 x 1 x 1.48 m box) is centred at (-1, -2), heading +x. From above: its roof at 1.49 m.
  es->SetTime(1.0);
  RayHit hit = es->Intersect(Eigen::Vector3d(-1, -2, 2.5), -Eigen::Vector3d::UnitZ(), 10.0);
  ASSERT_TRUE(hit.hit);
  EXPECT_EQ(hit.object_id, 0);
  EXPECT_NEAR(hit.distance_m, 1.01, 1e-5);
  EXPECT_TRUE(hit.normal_world.isApprox(Eigen::Vector3d::UnitZ(), 1e-9));
  // From the side (+y of the car): its +y face, normal +y.
  hit = es->Intersect(Eigen::Vector3d(-1, 0, 0.5), -Eigen::Vector3d::UnitY(), 10.0);
  ASSERT_TRUE(hit.hit);
  EXPECT_EQ(hit.object_id, 0);
  EXPECT_NEAR(hit.distance_m, 1.5, 1e-5);
  EXPECT_TRUE(hit.normal_world.isApprox(Eigen::Vector3d::UnitY(), 1e-6));
  // t = 4.5 s: 9 m along = 6 m leg + 3 m up the +y leg: centred at (3, 1), heading +y. The old spot shows the
  // floor; the new one the car, whose side normal has turned with it (its +y face now faces -x).
  es->SetTime(4.5);
  hit = es->Intersect(Eigen::Vector3d(-1, -2, 2.5), -Eigen::Vector3d::UnitZ(), 10.0);
  ASSERT_TRUE(hit.hit);
  EXPECT_EQ(hit.object_id, -1);
  EXPECT_NEAR(hit.distance_m, 2.5, 1e-5);
  hit = es->Intersect(Eigen::Vector3d(1, 1, 0.5), Eigen::Vector3d::UnitX(), 10.0);
  ASSERT_TRUE(hit.hit);
  EXPECT_EQ(hit.object_id, 0);
  EXPECT_NEAR(hit.distance_m, 1.5, 1e-5);
  EXPECT_TRUE(hit.normal_world.isApprox(-Eigen::Vector3d::UnitX(), 1e-6));
  EXPECT_TRUE(es->object_pose(0).isApprox(DynamicObjectPose(scene.dynamic_objects[0], 4.5), 1e-12));
  EXPECT_EQ(es->time(), 4.5);
}

TEST(EmbreeScene, InstancedScenesMatchFlatMeshesRayForRay) {
  // The same surfaces, once as a flat mesh (BuildMeshAt) and once instanced (static + object) at the same t:
  // batched and single rays agree with each other and with the flat mesh.
  const Scene scene = testing::RoomWithCar();
  const double t = 2.7;
  std::unique_ptr<EmbreeScene> instanced, flat;
  ASSERT_TRUE(EmbreeScene::Create(scene, &instanced, t).ok);
  ASSERT_TRUE(EmbreeScene::Create(BuildMeshAt(scene, t), &flat).ok);
  RandomStream rng(5, "test.instanced");
  std::vector<RayQuery> q;
  for (int i = 0; i < 3000; ++i) q.push_back({RandomInside(scene.bounds, 0.05, &rng), RandomUnit(&rng), 50.0});
  std::vector<RayHit> batch(q.size());
  instanced->IntersectBatch(q.data(), q.size(), batch.data());
  int on_car = 0;
  for (size_t i = 0; i < q.size(); ++i) {
    const RayHit a = instanced->Intersect(q[i].origin_world, q[i].dir_world, 50.0);
    const RayHit b = flat->Intersect(q[i].origin_world, q[i].dir_world, 50.0);
    ASSERT_TRUE(a.hit && b.hit);
    EXPECT_EQ(batch[i].distance_m, a.distance_m);
    EXPECT_EQ(batch[i].object_id, a.object_id);
    EXPECT_NEAR(a.distance_m, b.distance_m, 1e-5);  // float rounding differs between the two layouts
    EXPECT_TRUE(a.normal_world.isApprox(b.normal_world, 1e-5));
    EXPECT_EQ(a.material_id, b.material_id);
    on_car += a.object_id == 0;
  }
  EXPECT_GT(on_car, 30);  // some rays do see the car
}

/// The distinct static triangles VisitStaticTrianglesNear offers around p without pruning.
std::set<int> VisitedNear(const EmbreeScene& es, const Eigen::Vector3d& p, double radius_m) {
  std::set<int> ids;
  es.VisitStaticTrianglesNear(p, radius_m, [&](int id) {
    ids.insert(id);
    return radius_m;
  });
  return ids;
}

TEST(EmbreeScene, PointQueryOffersEveryStaticTriangleNearThePoint) {
  Scene scene;
  ASSERT_TRUE(LoadScene(testing::BoxRoomPath(), &scene).ok);
  const TriangleMesh mesh = BuildMesh(scene);
  const auto es = testing::MakeEmbree(scene);
  // Unpruned, a radius beyond the scene reaches every triangle.
  const Eigen::Vector3d centre = scene.bounds.center();
  EXPECT_EQ(VisitedNear(*es, centre, 1e3).size(), mesh.triangles.size());
  RandomStream rng(11, "test.point_query");
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p = RandomInside(scene.bounds, 0.02, &rng);
    const std::set<int> ids = VisitedNear(*es, p, 1.0);
    for (int id : ids) ASSERT_TRUE(id >= 0 && id < static_cast<int>(mesh.triangles.size())) << id;
    // A triangle with a vertex inside the sphere reaches into it: it must be offered (float bounds: 1e-4 m slack).
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      bool near = false;
      for (int k = 0; k < 3; ++k) near |= (mesh.vertices_m[mesh.triangles[t][k]] - p).norm() < 1.0 - 1e-4;
      if (near) {
        EXPECT_TRUE(ids.count(static_cast<int>(t))) << "point " << i << ", triangle " << t;
      }
    }
  }
  // A visitor that answers 0 prunes the search to the triangles whose bounds touch the point itself.
  std::size_t pruned = 0;
  es->VisitStaticTrianglesNear(centre, 1e3, [&](int) { return ++pruned, 0.0; });
  EXPECT_LT(pruned, mesh.triangles.size());
}

TEST(EmbreeScene, PointQueryIgnoresDynamicObjects) {
  // The instanced static world offers what the same scene without its car offers, point for point.
  const Scene with_car = testing::RoomWithCar();
  std::unique_ptr<EmbreeScene> instanced;
  ASSERT_TRUE(EmbreeScene::Create(with_car, &instanced, 0.0).ok);
  const auto flat = testing::MakeEmbree(testing::PlainRoom());
  RandomStream rng(13, "test.point_query_dynamic");
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p = RandomInside(with_car.bounds, 0.02, &rng);
    EXPECT_EQ(VisitedNear(*instanced, p, 1.5), VisitedNear(*flat, p, 1.5)) << "point " << i;
  }
}

}  // namespace
}  // namespace rotolidar::sim
