// truth/dynamic_hits.csv as the sim writes it (sim/sim_runner.cpp): a short run among walkers writes returns that
// lie on a walker's body at its true pose and off the static world, byte-identical for the same seed; a scene
// without dynamic objects writes the header only.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "sim/sim_runner.hpp"
#include "sim/truth/truth.hpp"
#include "sim/world/embree_scene.hpp"
#include "sim/world/scene_dynamic.hpp"

namespace rotolidar::sim {
namespace {

namespace fs = std::filesystem;

std::string ReadAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Distance from p to the segment [a, b].
double SegmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double u = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + u * ab - p).norm();
}

/// Distance from p to triangle (a, b, c): to its plane when p projects inside it, else to its nearest edge.
double TriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
  const Eigen::Vector3d q = p - n.dot(p - a) * n;
  const bool inside = (b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
                      (a - c).cross(q - c).dot(n) >= 0;
  if (inside) return std::abs(n.dot(p - a));
  return std::min({SegmentDistance(p, a, b), SegmentDistance(p, b, c), SegmentDistance(p, c, a)});
}

double MeshDistance(const TriangleMesh& mesh, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const auto& v = mesh.vertices_m;
    best = std::min(best, TriangleDistance(p, v[t[0]], v[t[1]], v[t[2]]));
  }
  return best;
}

/// Distance from p to the static world when some triangle lies within radius_m, else radius_m.
double StaticDistanceWithin(const EmbreeScene& bvh, const TriangleMesh& mesh, const Eigen::Vector3d& p,
                            double radius_m) {
  double best = radius_m;
  bvh.VisitStaticTrianglesNear(p, radius_m, [&](int id) {
    const Eigen::Vector3i& t = mesh.triangles[static_cast<size_t>(id)];
    best = std::min(best, TriangleDistance(p, mesh.vertices_m[t[0]], mesh.vertices_m[t[1]], mesh.vertices_m[t[2]]));
    return best;
  });
  return best;
}

/// One second of the default rig, carried along the scene's own path (`from_scene`) or the default loop.
SimConfig ShortRun(const std::string& scene, bool from_scene) {
  SimConfig c = DefaultSimConfig();
  c.scene = scene;
  c.carrier_from_scene = from_scene;
  c.camera.enabled = false;
  c.duration_s = 1.0;
  return c;
}

fs::path Simulate(const SimConfig& config, const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rotolidar_dynamic_hits_" + name);
  fs::remove_all(dir);
  SimSummary summary;
  const Status s = RunSimulation(config, dir.string(), &summary);
  EXPECT_TRUE(s.ok) << s.message;
  return dir;
}

// lab_people: walkers crossing the lab around the rig's start. Each return lies on its walker's body at the
// walker's pose at the firing time (Embree poses the objects once per packet, 1.3 ms, < 2 mm of walking), and
// nearly all lie more than 0.1 m from the static world (a foot on the floor is the exception).
TEST(DynamicHitsSim, ReturnsLieOnTheWalkerAtItsTruePoseAndOffTheStaticWorld) {
  const SimConfig config = ShortRun("lab_people", true);
  const fs::path dir = Simulate(config, "a");
  std::vector<DynamicHitSample> hits;
  const Status r = ReadDynamicHits(dir.string(), &hits);
  ASSERT_TRUE(r.ok) << r.message;
  ASSERT_GT(hits.size(), 200u);

  Scene scene;
  ASSERT_TRUE(LoadScene(ResolveScenePath(config.scene), &scene).ok);
  std::vector<TriangleMesh> bodies;
  for (const DynamicObject& o : scene.dynamic_objects) bodies.push_back(BuildObjectMesh(scene, o));
  const TriangleMesh world = BuildMesh(scene);
  std::unique_ptr<EmbreeScene> bvh;
  ASSERT_TRUE(EmbreeScene::Create(world, &bvh).ok);
  size_t off_static = 0;
  double worst_body_m = 0.0, last_t = -1.0;
  for (const DynamicHitSample& h : hits) {
    ASSERT_GE(h.t_s, last_t);  // in firing order
    last_t = h.t_s;
    ASSERT_GE(h.object_id, 0);
    ASSERT_LT(h.object_id, static_cast<int>(bodies.size()));
    const DynamicObject& o = scene.dynamic_objects[static_cast<size_t>(h.object_id)];
    const Eigen::Vector3d p_body = DynamicObjectPose(o, h.t_s).inverse() * h.p_world;
    worst_body_m = std::max(worst_body_m, MeshDistance(bodies[static_cast<size_t>(h.object_id)], p_body));
    off_static += StaticDistanceWithin(*bvh, world, h.p_world, 0.1) >= 0.1;
  }
  EXPECT_LT(worst_body_m, 0.01);
  EXPECT_GT(off_static, hits.size() * 9 / 10) << off_static << " of " << hits.size();

  // The same seed writes the same bytes.
  const fs::path again = Simulate(config, "b");
  EXPECT_EQ(ReadAll(dir / "truth" / "dynamic_hits.csv"), ReadAll(again / "truth" / "dynamic_hits.csv"));
  fs::remove_all(dir);
  fs::remove_all(again);
}

TEST(DynamicHitsSim, ASceneWithoutDynamicObjectsWritesTheHeaderOnly) {
  const SimConfig config = ShortRun("box_room", false);
  Scene scene;
  ASSERT_TRUE(LoadScene(ResolveScenePath(config.scene), &scene).ok);
  ASSERT_TRUE(scene.dynamic_objects.empty());
  const fs::path dir = Simulate(config, "static");
  EXPECT_EQ(ReadAll(dir / "truth" / "dynamic_hits.csv"), "t_s,object_id,x_m,y_m,z_m\n");
  std::vector<DynamicHitSample> hits;
  ASSERT_TRUE(ReadDynamicHits(dir.string(), &hits).ok);
  EXPECT_TRUE(hits.empty());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rotolidar::sim
