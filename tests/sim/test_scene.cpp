// Scene loader and mesh builder: the shipped room loads, errors name file:line and the key, meshes are
// deterministic and faces point the way the format promises.
#include <fstream>

#include <gtest/gtest.h>

#include "sim/world/scene.hpp"
#include "tests/sim/world_fixtures.hpp"

namespace rotolidar::sim {
namespace {

std::string WriteTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

const char* kMinimalHead =
    "format_version: 1\n"                                        // line 1
    "closed: true\n"                                             // 2
    "bounds: {min: [-1, -1, 0], max: [1, 1, 2]}\n"               // 3
    "materials:\n"                                               // 4
    "  - {name: white, albedo: 0.8}\n"                           // 5
    "primitives:\n";                                             // 6

Eigen::Vector3d Centroid(const TriangleMesh& m, size_t t) {
  const Eigen::Vector3i& tri = m.triangles[t];
  return (m.vertices_m[tri[0]] + m.vertices_m[tri[1]] + m.vertices_m[tri[2]]) / 3.0;
}

Eigen::Vector3d FrontNormal(const TriangleMesh& m, size_t t) {
  const Eigen::Vector3i& tri = m.triangles[t];
  return (m.vertices_m[tri[1]] - m.vertices_m[tri[0]]).cross(m.vertices_m[tri[2]] - m.vertices_m[tri[0]]);
}

TEST(Scene, LoadsBoxRoom) {
  Scene scene;
  const Status s = LoadScene(testing::BoxRoomPath(), &scene);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(scene.name, "box_room");
  EXPECT_TRUE(scene.closed);
  EXPECT_EQ(scene.materials.size(), 9u);
  EXPECT_EQ(scene.primitives.size(), 13u);
  ASSERT_EQ(scene.elements.size(), 4u);
  EXPECT_EQ(scene.elements[0].type, "door");
  EXPECT_NEAR(scene.elements[0].width_m, 0.9, 1e-12);
  const int sign = scene.FindMaterial("sign_retro");
  ASSERT_GE(sign, 0);
  EXPECT_TRUE(scene.materials[sign].retroreflective);
  const TriangleMesh mesh = BuildMesh(scene);
  // 8 boxes x 12 + 3 quads x 2 + 2 cylinders x 4 x 32 segments.
  EXPECT_EQ(mesh.triangles.size(), 8u * 12 + 3 * 2 + 2 * 4 * 32);
  EXPECT_EQ(mesh.material_ids.size(), mesh.triangles.size());
  EXPECT_EQ(mesh.primitive_ids.size(), mesh.triangles.size());
}

TEST(Scene, UnknownKeyErrorNamesLineAndKey) {
  const std::string path = WriteTemp("unknown_key.yaml", std::string(kMinimalHead) +
      "  - {type: box, center: [0, 0, 1], size: [1, 1, 1], material: white}\n"   // 7
      "  - type: box\n"                                                          // 8
      "    center: [0, 0, 1]\n"                                                  // 9
      "    colour: red\n"                                                        // 10
      "    size: [1, 1, 1]\n"
      "    material: white\n");
  Scene scene;
  const Status s = LoadScene(path, &scene);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find(path + ":10:"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("colour"), std::string::npos) << s.message;
}

TEST(Scene, BadValuesNameLineAndKey) {
  struct Case { std::string body; std::string line; std::string key; };
  const std::vector<Case> cases = {
      {"  - {type: box, center: [0, 0], size: [1, 1, 1], material: white}\n", ":7:", "center"},
      {"  - {type: box, center: [0, 0, 1], size: [1, 1, 1], material: black}\n", ":7:", "black"},
      {"  - {type: cone, center: [0, 0, 1], material: white}\n", ":7:", "cone"},
      {"  - {type: cylinder, center: [0, 0, 1], radius: abc, height: 1, material: white}\n", ":7:", "radius"},
      {"  - {type: box, center: [0, 0, 1], size: [1, -1, 1], material: white}\n", ":7:", "size"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    const std::string path = WriteTemp("bad_" + std::to_string(i) + ".yaml", kMinimalHead + cases[i].body);
    Scene scene;
    const Status s = LoadScene(path, &scene);
    ASSERT_FALSE(s.ok) << cases[i].body;
    EXPECT_NE(s.message.find(cases[i].line), std::string::npos) << s.message;
    EXPECT_NE(s.message.find(cases[i].key), std::string::npos) << s.message;
  }
  std::string bad_albedo = kMinimalHead;
  bad_albedo.replace(bad_albedo.find("0.8"), 3, "1.5");
  Scene scene;
  const Status s = LoadScene(WriteTemp("albedo.yaml", bad_albedo + "  - {type: box, center: [0,0,1], size: [1,1,1], "
                                                                     "material: white}\n"), &scene);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find(":5:"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("albedo"), std::string::npos) << s.message;
}

TEST(Scene, MissingFileAndSyntaxErrors) {
  Scene scene;
  Status s = LoadScene("/nonexistent/room.yaml", &scene);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("/nonexistent/room.yaml"), std::string::npos);
  s = LoadScene(WriteTemp("syntax.yaml", std::string(kMinimalHead) + "  - {type: box, center: [0, 0\n"), &scene);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("syntax.yaml:"), std::string::npos) << s.message;
}

TEST(Scene, LoadingTwiceGivesIdenticalMesh) {
  Scene a, b;
  ASSERT_TRUE(LoadScene(testing::BoxRoomPath(), &a).ok);
  ASSERT_TRUE(LoadScene(testing::BoxRoomPath(), &b).ok);
  const TriangleMesh ma = BuildMesh(a), mb = BuildMesh(b);
  ASSERT_EQ(ma.vertices_m.size(), mb.vertices_m.size());
  for (size_t i = 0; i < ma.vertices_m.size(); ++i) EXPECT_EQ(ma.vertices_m[i], mb.vertices_m[i]);
  ASSERT_EQ(ma.triangles.size(), mb.triangles.size());
  for (size_t i = 0; i < ma.triangles.size(); ++i) EXPECT_EQ(ma.triangles[i], mb.triangles[i]);
  EXPECT_EQ(ma.material_ids, mb.material_ids);
}

TEST(Scene, InwardBoxFacesPointInsideOutwardOutside) {
  for (bool inward : {true, false}) {
    TriangleMesh mesh;
    const Eigen::Vector3d center(1, 2, 3);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    AppendBox(center, R, Eigen::Vector3d(2, 3, 4), inward, {0, 1, 2, 3, 4, 5}, 0, &mesh);
    ASSERT_EQ(mesh.triangles.size(), 12u);
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const double d = FrontNormal(mesh, t).dot(center - Centroid(mesh, t));
      EXPECT_EQ(d > 0.0, inward) << "triangle " << t;
    }
    // Face f has material f: the -z face (4) lies below the centre in the box frame.
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      if (mesh.material_ids[t] != 4) continue;
      EXPECT_NEAR((R.transpose() * (Centroid(mesh, t) - center)).z(), -2.0, 1e-9);
    }
  }
}

TEST(Scene, CylinderFacesPointOutward) {
  Scene scene;
  ASSERT_TRUE(LoadScene(testing::BoxRoomPath(), &scene).ok);
  const TriangleMesh mesh = BuildMesh(scene);
  int checked = 0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Primitive& p = scene.primitives[mesh.primitive_ids[t]];
    if (p.type != PrimitiveType::kCylinder) continue;
    EXPECT_LT(FrontNormal(mesh, t).dot(p.center_m - Centroid(mesh, t)), 0.0);
    ++checked;
  }
  EXPECT_EQ(checked, 2 * 4 * 32);
}

}  // namespace
}  // namespace rotolidar::sim
