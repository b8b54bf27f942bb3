// The shipped scenes (scenes/*.yaml): they load, closed ones are closed, annotated elements match the geometry
// (rays through openings, onto frames and columns), default paths are free of obstacles, loading is
// bit-for-bit repeatable, and the element truth file round-trips.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <gtest/gtest.h>

#include "sim/world/mesh_io.hpp"
#include "sim/world/scene_dynamic.hpp"
#include "tests/sim/world/world_fixtures.hpp"
#include "core/util/log.hpp"

namespace rotolidar::sim {
namespace {

using testing::SceneNames;
using testing::ScenePath;

constexpr double kPi = 3.14159265358979323846;

struct Loaded {
  Scene scene;
  std::unique_ptr<EmbreeScene> embree;  ///< static world only
};

Loaded Load(const std::string& name) {
  Loaded l;
  const Status s = LoadScene(ScenePath(name), &l.scene);
  ROTOLIDAR_CHECK(s.ok, s.message);
  l.embree = testing::MakeEmbree(l.scene);
  return l;
}

TEST(SceneLibrary, ScenesFolderHoldsExactlyTheListedScenes) {
  std::set<std::string> on_disk;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(ROTOLIDAR_SOURCE_DIR) + "/scenes")) {
    if (entry.path().extension() == ".yaml") on_disk.insert(entry.path().stem().string());
  }
  EXPECT_EQ(on_disk, std::set<std::string>(SceneNames().begin(), SceneNames().end()));
}

TEST(SceneLibrary, EverySceneLoadsWithItsNameAndBuilds) {
  for (const std::string& name : SceneNames()) {
    Scene scene;
    const Status s = LoadScene(ScenePath(name), &scene);
    ASSERT_TRUE(s.ok) << s.message;
    EXPECT_EQ(scene.name, name);
    std::string error;
    EXPECT_TRUE(scene.Validate(&error)) << name << ": " << error;
    std::unique_ptr<EmbreeScene> es;
    const Status e = EmbreeScene::Create(scene, &es);
    ASSERT_TRUE(e.ok) << name << ": " << e.message;
    EXPECT_GT(es->num_triangles(), 0u);
    EXPECT_EQ(es->num_dynamic_objects(), scene.dynamic_objects.size());
  }
}

TEST(SceneLibrary, LoadingTwiceGivesIdenticalBytes) {
  for (const std::string& name : SceneNames()) {
    Scene a, b;
    ASSERT_TRUE(LoadScene(ScenePath(name), &a).ok);
    ASSERT_TRUE(LoadScene(ScenePath(name), &b).ok);
    for (double t : {0.0, 7.3}) {
      const TriangleMesh ma = BuildMeshAt(a, t), mb = BuildMeshAt(b, t);
      ASSERT_EQ(ma.vertices_m.size(), mb.vertices_m.size()) << name;
      ASSERT_EQ(ma.triangles.size(), mb.triangles.size()) << name;
      EXPECT_EQ(0, std::memcmp(ma.vertices_m.data(), mb.vertices_m.data(), ma.vertices_m.size() * sizeof(double) * 3))
          << name;
      EXPECT_EQ(0, std::memcmp(ma.triangles.data(), mb.triangles.data(), ma.triangles.size() * sizeof(int) * 3))
          << name;
      EXPECT_EQ(ma.material_ids, mb.material_ids) << name;
    }
  }
}

TEST(SceneLibrary, ClosedScenesNeverLetARayEscape) {
  int closed = 0;
  for (const std::string& name : SceneNames()) {
    Scene scene;
    ASSERT_TRUE(LoadScene(ScenePath(name), &scene).ok);
    if (!scene.closed) continue;
    ++closed;
    std::unique_ptr<EmbreeScene> es;
    ASSERT_TRUE(EmbreeScene::Create(scene, &es).ok);
    RandomStream rng(11, "test.closed." + name);
    const double diagonal_m = scene.bounds.diagonal().norm();
    for (double t : {0.0, 4.1, 13.7}) {
      es->SetTime(t);
      for (int i = 0; i < 3000; ++i) {
        const Eigen::Vector3d o = testing::RandomInside(scene.bounds, 0.02, &rng);
        const Eigen::Vector3d d = testing::RandomUnit(&rng);
        const RayHit hit = es->Intersect(o, d, 1e4);
        ASSERT_TRUE(hit.hit) << name << ": ray " << i << " from " << o.transpose() << " along " << d.transpose()
                             << " escaped at t = " << t;
        EXPECT_LE(hit.distance_m, diagonal_m + 1.0) << name;
      }
    }
  }
  EXPECT_EQ(closed, 8);  // box_room, corridor, corridor_busy, garage, glass_atrium, lab, lab_people, tunnel
}

/// Doors and windows: rays along the element's x from 0.3 m in front of its near face. Inside the opening
/// (inset 5 cm) an open element lets them through the whole depth, a closed one stops them within the depth
/// (its leaf or pane); 5 cm outside the left, right and top edges they hit the wall at the near face.
void CheckOpening(const EmbreeScene& es, const AnnotatedElement& e, const std::string& where) {
  constexpr double kStandoff = 0.3, kTol = 0.02;  // leaves and panes sit up to 1 cm off the nominal faces
  const Eigen::Isometry3d T = e.T_world_element();
  const Eigen::Vector3d x = T.linear().col(0), y = T.linear().col(1), z = T.linear().col(2);
  const auto origin = [&](double a, double b) {
    return Eigen::Vector3d(T.translation() - x * (0.5 * e.depth_m + kStandoff) + y * a + z * b);
  };
  const double wi = 0.5 * e.width_m - 0.05, hi = 0.5 * e.height_m - 0.05;
  for (double a : {-wi, 0.0, wi}) {
    for (double b : {-hi, 0.0, hi}) {
      const RayHit hit = es.Intersect(origin(a, b), x, 100.0);
      if (e.open) {
        EXPECT_TRUE(!hit.hit || hit.distance_m > kStandoff + e.depth_m + 0.05) << where << " blocked at " << a << ","
                                                                               << b << ": " << hit.distance_m;
      } else {
        ASSERT_TRUE(hit.hit) << where;
        EXPECT_GE(hit.distance_m, kStandoff - kTol) << where;
        EXPECT_LE(hit.distance_m, kStandoff + e.depth_m + kTol) << where << " at " << a << "," << b;
      }
    }
  }
  const double wo = 0.5 * e.width_m + 0.05, ho = 0.5 * e.height_m + 0.05;
  for (const auto& [a, b] : {std::pair{-wo, 0.0}, {wo, 0.0}, {0.0, ho}}) {
    const RayHit hit = es.Intersect(origin(a, b), x, 100.0);
    ASSERT_TRUE(hit.hit) << where << " frame at " << a << "," << b;
    EXPECT_NEAR(hit.distance_m, kStandoff, kTol) << where << " frame at " << a << "," << b;
  }
}

/// Columns: the named primitive has the stated dimensions, and horizontal rays towards the centre from the
/// four sides of the element frame hit its surface at the stated half width / half depth.
void CheckColumn(const Scene& scene, const EmbreeScene& es, const AnnotatedElement& e, const std::string& where) {
  ASSERT_FALSE(e.primitive.empty()) << where << ": columns name their primitive";
  const Primitive* p = nullptr;
  for (const Primitive& q : scene.primitives) p = q.name == e.primitive ? &q : p;
  ASSERT_NE(p, nullptr) << where << ": no primitive " << e.primitive;
  EXPECT_NEAR((p->center_m - e.center_m).head<2>().norm(), 0.0, 1e-9) << where;
  double facet_tol = 1e-4;  // float vertices
  if (p->type == PrimitiveType::kCylinder) {
    EXPECT_NEAR(2.0 * p->radius_m, e.width_m, 1e-9) << where;
    EXPECT_NEAR(e.depth_m, e.width_m, 1e-9) << where;
    EXPECT_LE(std::abs(p->height_m - e.height_m), 0.02 + 1e-9) << where;  // columns reach 1 cm into floor/ceiling
    facet_tol += p->radius_m * (1.0 - std::cos(kPi / p->segments));      // polygon inside the true circle
  } else {
    ASSERT_EQ(p->type, PrimitiveType::kBox) << where;
    EXPECT_NEAR(p->size_m.x(), e.depth_m, 1e-9) << where;
    EXPECT_NEAR(p->size_m.y(), e.width_m, 1e-9) << where;
    EXPECT_LE(std::abs(p->size_m.z() - e.height_m), 0.02 + 1e-9) << where;
  }
  const Eigen::Matrix3d R = e.T_world_element().linear();
  constexpr double kStandoff = 0.5;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d d = R * Eigen::Vector3d(std::cos(k * kPi / 2), std::sin(k * kPi / 2), 0.0);
    const double half = 0.5 * (k % 2 ? e.width_m : e.depth_m);
    const RayHit hit = es.Intersect(e.center_m - d * (half + kStandoff), d, 100.0);
    ASSERT_TRUE(hit.hit) << where << " side " << k;
    EXPECT_GE(hit.distance_m, kStandoff - 1e-4) << where << " side " << k;
    EXPECT_LE(hit.distance_m, kStandoff + facet_tol) << where << " side " << k;
  }
}

TEST(SceneLibrary, AnnotatedElementsMatchTheGeometry) {
  int doors = 0, windows = 0, columns = 0;
  for (const std::string& name : SceneNames()) {
    const Loaded l = Load(name);
    for (const AnnotatedElement& e : l.scene.elements) {
      const std::string where = name + "/" + e.name;
      if (e.type == "column") {
        CheckColumn(l.scene, *l.embree, e, where);
        ++columns;
      } else {
        CheckOpening(*l.embree, e, where);
        ++(e.type == "door" ? doors : windows);
      }
    }
  }
  EXPECT_GE(doors, 20);
  EXPECT_GE(windows, 6);
  EXPECT_GE(columns, 40);
}

/// The space a carrier sweeps: half width and heights above the ground [m].
struct Envelope {
  double half_width_m;
  std::vector<double> heights_m;
};

TEST(SceneLibrary, DefaultPathsAreFreeOfStaticObstacles) {
  const std::map<std::string, Envelope> envelopes = {
      {"handheld", {0.25, {0.4, 1.0, 1.6}}}, {"wheeled", {0.3, {0.25, 0.6}}}, {"car", {0.9, {0.5, 1.4}}}};
  int segments = 0;
  for (const std::string& name : SceneNames()) {
    const Loaded l = Load(name);
    for (const auto& [carrier, path] : l.scene.default_paths) {
      const Envelope& env = envelopes.at(carrier);
      for (std::size_t i = 1; i < path.size(); ++i) {
        const Eigen::Vector2d a(path[i - 1].x_m, path[i - 1].y_m), b(path[i].x_m, path[i].y_m);
        if ((b - a).norm() < 1e-9) continue;
        const Eigen::Vector2d u = (b - a).normalized(), n(-u.y(), u.x());
        for (double off : {-env.half_width_m, 0.0, env.half_width_m}) {
          const Eigen::Vector2d pa = a + n * off, pb = b + n * off;
          const double za = testing::GroundZ(*l.embree, l.scene, pa.x(), pa.y());
          const double zb = testing::GroundZ(*l.embree, l.scene, pb.x(), pb.y());
          ASSERT_TRUE(std::isfinite(za) && std::isfinite(zb)) << name << "/" << carrier << ": no ground";
          for (double h : env.heights_m) {
            const Eigen::Vector3d from(pa.x(), pa.y(), za + h), to(pb.x(), pb.y(), zb + h);
            const RayHit hit = l.embree->Intersect(from, to - from, (to - from).norm());
            EXPECT_FALSE(hit.hit) << name << "/" << carrier << " segment " << i << " offset " << off << " height "
                                  << h << ": blocked after " << hit.distance_m << " m at "
                                  << (from + hit.distance_m * (to - from).normalized()).transpose();
          }
        }
        ++segments;
      }
    }
  }
  EXPECT_GT(segments, 100);
}

double PathLength2d(const std::vector<Waypoint2d>& path) {
  double length = 0.0;
  for (std::size_t i = 1; i < path.size(); ++i) {
    length += std::hypot(path[i].x_m - path[i - 1].x_m, path[i].y_m - path[i - 1].y_m);
  }
  return length;
}

TEST(SceneLibrary, ScenesHaveTheSeedsShapes) {
  const Loaded parking = Load("parking");
  const auto& loop = parking.scene.default_paths.at("handheld");
  EXPECT_NEAR(PathLength2d(loop), 120.0, 12.0);  // the seed walked ~120 m in 202 s
  EXPECT_EQ(loop.front().x_m, loop.back().x_m);
  EXPECT_EQ(loop.front().y_m, loop.back().y_m);
  EXPECT_GE(parking.scene.dynamic_objects.size(), 4u);
  const Loaded corridor = Load("corridor");
  const Eigen::Vector3d c = corridor.scene.bounds.sizes();
  EXPECT_GE(c.x(), 60.0);
  EXPECT_LE(c.x(), 100.0);
  EXPECT_LE(c.y(), 2.5);
  const Loaded garage = Load("garage");
  EXPECT_LT(garage.scene.lighting.ambient, 0.1);  // low light for the camera
  const Loaded urban = Load("urban_loop");
  const auto& drive = urban.scene.default_paths.at("car");
  EXPECT_GT(PathLength2d(drive), 500.0);
  // KittiPath's frame: the drive starts at the origin moving along +x (cam0 z forward = base x); KITTI 07
  // turns left at once, so 6 m on the heading is still within 45 degrees of +x.
  EXPECT_NEAR(drive.front().x_m, 0.0, 1e-9);
  EXPECT_NEAR(drive.front().y_m, 0.0, 1e-9);
  EXPECT_GT(drive[1].x_m, std::abs(drive[1].y_m));
  // A loop: the end comes back within 15 m of the start.
  EXPECT_LT(std::hypot(drive.back().x_m, drive.back().y_m), 15.0);
}

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(cell);
  return out;
}

TEST(SceneLibrary, ElementTruthFileRoundTrips) {
  const Loaded l = Load("lab");
  const std::string path = ::testing::TempDir() + "/lab_elements.csv";
  ASSERT_TRUE(WriteElementTruth(l.scene, path).ok);
  std::ifstream file(path);
  std::string line;
  ASSERT_TRUE(std::getline(file, line));
  EXPECT_EQ(line, "name,type,frame,x_m,y_m,z_m,qw,qx,qy,qz,yaw_rad,width_m,height_m,depth_m,open");
  std::size_t row = 0;
  while (std::getline(file, line)) {
    const std::vector<std::string> c = SplitCsv(line);
    ASSERT_EQ(c.size(), 15u);
    ASSERT_LT(row, l.scene.elements.size());
    const AnnotatedElement& e = l.scene.elements[row++];
    EXPECT_EQ(c[0], e.name);
    EXPECT_EQ(c[1], e.type);
    EXPECT_EQ(c[2], "world");
    const Eigen::Vector3d t(std::stod(c[3]), std::stod(c[4]), std::stod(c[5]));
    EXPECT_EQ(t, e.center_m);  // 17 significant digits: exact
    const Eigen::Quaterniond q(std::stod(c[6]), std::stod(c[7]), std::stod(c[8]), std::stod(c[9]));
    EXPECT_TRUE(q.toRotationMatrix().isApprox(e.T_world_element().linear(), 1e-15));
    EXPECT_EQ(std::stod(c[11]), e.width_m);
    EXPECT_EQ(std::stod(c[12]), e.height_m);
    EXPECT_EQ(std::stod(c[13]), e.depth_m);
    EXPECT_EQ(c[14] == "1", e.open);
  }
  EXPECT_EQ(row, l.scene.elements.size());
}

TEST(SceneLibrary, MeshAssetsAreClosedAndOutward) {
  // Lower bounds of the volumes: sedan ~7.3 m^3, tree ~23.6 m^3, leaf_crown 800 leaves of 1 cm x 0.0173 m^2 / 3
  // = 0.046 m^3 (make_meshes.py).
  const std::map<std::string, double> min_volume_m3 = {
      {"sedan.obj", 1.0}, {"tree.ply", 1.0}, {"leaf_crown.ply", 0.04}};
  for (const auto& [file, min_volume] : min_volume_m3) {
    MeshAsset mesh;
    const Status s = LoadMeshFile(std::string(ROTOLIDAR_SOURCE_DIR) + "/scenes/meshes/" + file, &mesh);
    ASSERT_TRUE(s.ok) << s.message;
    // Closed: every directed edge has its reverse exactly once. Outward: positive signed volume.
    std::map<std::pair<int, int>, int> edges;
    double volume = 0.0;
    for (const Eigen::Vector3i& t : mesh.triangles) {
      for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
      volume += mesh.vertices_m[t[0]].dot(mesh.vertices_m[t[1]].cross(mesh.vertices_m[t[2]])) / 6.0;
    }
    for (const auto& [edge, count] : edges) {
      EXPECT_EQ(count, 1) << file;
      EXPECT_EQ(edges.count({edge.second, edge.first}), 1u) << file << " edge " << edge.first << "-" << edge.second;
    }
    EXPECT_GT(volume, min_volume) << file;
  }
}

}  // namespace
}  // namespace rotolidar::sim
