// Scene loader and mesh builder: the shipped room loads, errors name file:line and the key, meshes are
// deterministic and faces point the way the format promises; repeats, mesh files (PCL), dynamic objects,
// paths, textures and lighting parse as documented (docs/scene_format.md).
#include <fstream>

#include <gtest/gtest.h>

#include "sim/world/mesh_io.hpp"
#include "sim/world/scene.hpp"
#include "sim/world/scene_dynamic.hpp"
#include "tests/sim/world/world_fixtures.hpp"

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

TEST(Scene, RepeatExpandsPrimitivesAndElements) {
  const std::string path = WriteTemp("repeat.yaml", std::string(kMinimalHead) +
      "  - {type: box, name: col, center: [1, 2, 1], size: [0.5, 0.5, 2], material: white,\n"
      "     repeat: {count: [2, 3], step: [4, 5]}}\n"
      "elements:\n"
      "  - {name: col, type: column, center: [1, 2, 1], width: 0.5, height: 2, primitive: col,\n"
      "     repeat: {count: [2, 3], step: [4, 5]}}\n");
  Scene scene;
  const Status s = LoadScene(path, &scene);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_EQ(scene.primitives.size(), 6u);
  ASSERT_EQ(scene.elements.size(), 6u);
  for (size_t k = 0; k < 6; ++k) {
    const int i = static_cast<int>(k) / 3, j = static_cast<int>(k) % 3;
    const std::string suffix = "_" + std::to_string(i) + "_" + std::to_string(j);
    EXPECT_EQ(scene.primitives[k].name, "col" + suffix);
    EXPECT_EQ(scene.primitives[k].center_m, Eigen::Vector3d(1 + 4 * i, 2 + 5 * j, 1));
    EXPECT_EQ(scene.elements[k].primitive, "col" + suffix);  // copies pair with copies
    EXPECT_EQ(scene.elements[k].center_m, scene.primitives[k].center_m);
  }
  const std::string bad = WriteTemp("repeat_bad.yaml", std::string(kMinimalHead) +
      "  - {type: box, center: [1, 2, 1], size: [1, 1, 1], material: white, repeat: {count: [2], step: [1, 2]}}\n");
  const Status e = LoadScene(bad, &scene);
  ASSERT_FALSE(e.ok);
  EXPECT_NE(e.message.find(":7:"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("step"), std::string::npos) << e.message;
}

TEST(Scene, MeshFilesLoadThroughPclScaledAndPosed) {
  // A unit cube written with quads (PCL's OBJ reader keeps polygons; the loader fans them into triangles).
  const std::string obj = WriteTemp("cube.obj",
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
      "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
  MeshAsset cube;
  ASSERT_TRUE(LoadMeshFile(obj, &cube).ok);
  ASSERT_EQ(cube.triangles.size(), 12u);
  const std::string ply = ::testing::TempDir() + "/cube_copy.obj";
  ASSERT_TRUE(WriteObjFile(ply, cube).ok);
  MeshAsset again;
  ASSERT_TRUE(LoadMeshFile(ply, &again).ok);
  EXPECT_EQ(again.vertices_m, cube.vertices_m);
  EXPECT_EQ(again.triangles, cube.triangles);
  const std::string path = WriteTemp("mesh_scene.yaml", std::string(kMinimalHead) +
      "  - {type: mesh, name: m, file: cube.obj, center: [1, 0, 0], yaw_deg: 90, scale: [2, 1, 1], material: white}\n");
  Scene scene;
  const Status s = LoadScene(path, &scene);
  ASSERT_TRUE(s.ok) << s.message;
  const TriangleMesh mesh = BuildMesh(scene);
  ASSERT_EQ(mesh.triangles.size(), 12u);
  // Vertex (1, 0, 0) of the file: scaled to (2, 0, 0), turned 90 deg about z to (0, 2, 0), moved to (1, 2, 0).
  EXPECT_TRUE(mesh.vertices_m[1].isApprox(Eigen::Vector3d(1, 2, 0), 1e-12)) << mesh.vertices_m[1].transpose();
  const Eigen::AlignedBox3d box = mesh.Bounds();
  EXPECT_TRUE(box.min().isApprox(Eigen::Vector3d(0, 0, 0), 1e-12));
  EXPECT_TRUE(box.max().isApprox(Eigen::Vector3d(1, 2, 1), 1e-12));
  const std::string missing = WriteTemp("mesh_missing.yaml", std::string(kMinimalHead) +
      "  - {type: box, center: [0, 0, 1], size: [1, 1, 1], material: white}\n"
      "  - {type: mesh, file: nowhere.ply, center: [0, 0, 0], material: white}\n");
  const Status e = LoadScene(missing, &scene);
  ASSERT_FALSE(e.ok);
  EXPECT_NE(e.message.find(":8:"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("nowhere.ply"), std::string::npos) << e.message;
  const std::string bad_index = WriteTemp("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
  const Status b = LoadMeshFile(bad_index, &cube);
  EXPECT_FALSE(b.ok);
}

TEST(Scene, DynamicObjectsParseAndMoveAlongTheirPaths) {
  const std::string path = WriteTemp("dynamic.yaml", std::string(kMinimalHead) +
      "  - {type: box, center: [0, 0, 1], size: [1, 1, 1], material: white}\n"
      "dynamic:\n"
      "  - {name: walker, kind: person, material: white, speed: 1.5, loop: false, z: 0.5,\n"
      "     path: [[0, 0], [3, 0], [3, 4, 1.5]]}\n"
      "  - {name: loop_car, kind: car, material: white, speed: 2.0, start_offset: 1.0,\n"
      "     path: [[0, 0], [4, 0], [4, 3]]}\n");
  Scene scene;
  const Status s = LoadScene(path, &scene);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_EQ(scene.dynamic_objects.size(), 2u);
  const DynamicObject& walker = scene.dynamic_objects[0];
  EXPECT_EQ(walker.parts.size(), DefaultBody("person", 0).size());
  EXPECT_DOUBLE_EQ(PathLength(walker), 7.0);
  // t = 1 s: 1.5 m along +x, on the ground z = 0.5, facing +x.
  Eigen::Isometry3d T = DynamicObjectPose(walker, 1.0);
  EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(1.5, 0, 0.5), 1e-12));
  EXPECT_TRUE(T.linear().col(0).isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  // t = 4 s: 6 m = 3 m along x then 3 m of the 4 m leg up y; z interpolates 0.5 -> 1.5 over that leg.
  T = DynamicObjectPose(walker, 4.0);
  EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(3, 3, 1.25), 1e-12)) << T.translation().transpose();
  // Back and forth: at t = 6 s it walked 9 m = 7 m out and 2 m back, facing -y.
  T = DynamicObjectPose(walker, 6.0);
  EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(3, 2, 1.0), 1e-12)) << T.translation().transpose();
  EXPECT_TRUE(T.linear().col(0).isApprox(-Eigen::Vector3d::UnitY(), 1e-12));
  // A loop closes (length 4 + 3 + 5 = 12 m): poses repeat with period 6 s at 2 m/s.
  const DynamicObject& car = scene.dynamic_objects[1];
  EXPECT_DOUBLE_EQ(PathLength(car), 12.0);
  EXPECT_TRUE(DynamicObjectPose(car, 0.7).isApprox(DynamicObjectPose(car, 6.7), 1e-9));
  EXPECT_TRUE(DynamicObjectPose(car, 0.0).translation().isApprox(Eigen::Vector3d(1, 0, 0), 1e-12));
  const std::string bad = WriteTemp("dynamic_bad.yaml", std::string(kMinimalHead) +
      "  - {type: box, center: [0, 0, 1], size: [1, 1, 1], material: white}\n"
      "dynamic:\n"
      "  - {name: ghost, kind: person, material: white, speed: 1.0, path: [[0, 0]]}\n");
  const Status e = LoadScene(bad, &scene);
  ASSERT_FALSE(e.ok);
  EXPECT_NE(e.message.find(":9:"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("ghost"), std::string::npos) << e.message;
}

TEST(Scene, PathsTexturesAndLightingParse) {
  const std::string path = WriteTemp("extras.yaml", std::string(
      "format_version: 1\n"
      "bounds: {min: [-5, -5, 0], max: [5, 5, 3]}\n"
      "textures:\n"
      "  - {name: stripes_red, pattern: stripes, color_a: [1, 0, 0], size: 0.5, cells: 4}\n"
      "materials:\n"
      "  - {name: plain, albedo: 0.5}\n"
      "  - {name: red, albedo: 0.4, texture: stripes_red}\n"
      "  - {name: tinted, albedo: 0.4, texture: plaster, color: [0.2, 0.3, 0.4]}\n"
      "primitives:\n"
      "  - {type: box, center: [0, 0, 1.5], size: [10, 10, 3], inward: true, material: red}\n"
      "paths:\n"
      "  handheld: [[0, 0, 2.5], [1, 2], [3, -1, 0]]\n"
      "lighting: {ambient: 0.05, headlight: 0.1, lights: [{position: [0, 0, 2.9], intensity: 0.3}]}\n"
      "view: {eye: [0, -4, 2], target: [0, 0, 1]}\n"));
  Scene scene;
  const Status s = LoadScene(path, &scene);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_EQ(scene.default_paths.count("handheld"), 1u);
  const std::vector<Waypoint2d>& p = scene.default_paths.at("handheld");
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p[0].dwell_s, 2.5);
  EXPECT_EQ(p[1].x_m, 1.0);
  EXPECT_EQ(p[1].dwell_s, 0.0);
  EXPECT_EQ(scene.materials[0].color_rgb, Eigen::Vector3d::Constant(0.7));  // untextured default grey
  EXPECT_EQ(scene.materials[1].color_rgb, Eigen::Vector3d::Constant(1.0));  // textured default white
  EXPECT_EQ(scene.materials[2].color_rgb, Eigen::Vector3d(0.2, 0.3, 0.4));
  ASSERT_NE(FindTexture(scene.textures, "stripes_red"), nullptr);
  EXPECT_EQ(FindTexture(scene.textures, "stripes_red")->pattern, TexturePattern::kStripes);
  EXPECT_EQ(scene.lighting.ambient, 0.05);
  ASSERT_EQ(scene.lighting.lights.size(), 1u);
  EXPECT_TRUE(scene.view.set);

  struct Case { std::string text; std::string line; std::string key; };
  const std::string head = "format_version: 1\nbounds: {min: [-5, -5, 0], max: [5, 5, 3]}\nmaterials:\n";
  const std::string box = "primitives:\n  - {type: box, center: [0, 0, 1], size: [1, 1, 1], material: m}\n";
  const std::vector<Case> cases = {
      {head + "  - {name: m, albedo: 0.5, texture: moss}\n" + box, ":4:", "moss"},
      {head + "  - {name: m, albedo: 0.5, color: [1, 2, 0]}\n" + box, ":4:", "color"},
      {head + "  - {name: m, albedo: 0.5}\n" + box + "paths:\n  drone: [[0, 0], [1, 1]]\n", ":8:", "drone"},
      {head + "  - {name: m, albedo: 0.5}\n" + box + "paths:\n  car: [[0, 0], [9, 1]]\n", ":", "outside the bounds"},
      {head + "  - {name: m, albedo: 0.5}\n" + box + "lighting: {ambient: 2}\n", ":7:", "ambient"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    const Status e = LoadScene(WriteTemp("extras_bad_" + std::to_string(i) + ".yaml", cases[i].text), &scene);
    ASSERT_FALSE(e.ok) << i;
    EXPECT_NE(e.message.find(cases[i].line), std::string::npos) << e.message;
    EXPECT_NE(e.message.find(cases[i].key), std::string::npos) << e.message;
  }
}

TEST(Scene, BuildMeshAtPlacesDynamicBodies) {
  const Scene scene = testing::RoomWithCar();
  const TriangleMesh fixed = BuildMesh(scene), at = BuildMeshAt(scene, 1.0);
  ASSERT_EQ(at.triangles.size(), fixed.triangles.size() + 12);  // the car's one box
  // t = 1 s at 2 m/s from (-3, -2): the body's centre is at (-1, -2, 0.75).
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (size_t v = fixed.vertices_m.size(); v < at.vertices_m.size(); ++v) mean += at.vertices_m[v];
  mean /= static_cast<double>(at.vertices_m.size() - fixed.vertices_m.size());
  EXPECT_TRUE(mean.isApprox(Eigen::Vector3d(-1, -2, 0.75), 1e-12)) << mean.transpose();
  EXPECT_EQ(at.primitive_ids.back(), -1);  // object 0
}

}  // namespace
}  // namespace rotolidar::sim
