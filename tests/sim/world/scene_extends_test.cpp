// `extends`: a scene file that starts from another (docs/scene_format.md, 'Extending a scene'): it inherits the
// base's primitives, materials, elements, dynamic objects, paths and settings, adds to the lists, overrides
// scalars, paths per carrier and materials by name; a missing base, an error in the base, a cycle, keys the
// format does not know and names defined twice are errors naming the file and line.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "sim/world/scene.hpp"
#include "sim/world/scene_dynamic.hpp"
#include "tests/sim/world/world_fixtures.hpp"

namespace rotolidar::sim {
namespace {

/// A fresh folder per test (the files name each other by relative path).
std::string Folder(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "/extends_" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

void Write(const std::string& dir, const std::string& file, const std::string& text) {
  std::ofstream(dir + "/" + file) << text;
}

const char* kBase =
    "format_version: 1\n"
    "name: base\n"
    "description: the base\n"
    "closed: true\n"
    "bounds: {min: [-5, -5, 0], max: [5, 5, 3]}\n"
    "materials:\n"
    "  - {name: wall, albedo: 0.8}\n"
    "  - {name: glass, albedo: 0.05}\n"
    "primitives:\n"
    "  - {type: box, name: room, center: [0, 0, 1.5], size: [10, 10, 3], inward: true, material: wall}\n"
    "  - {type: quad, name: pane, center: [0, 4.9, 1.5], size: [1, 1], rpy_deg: [90, 0, 0], material: glass}\n"
    "elements:\n"
    "  - {name: col, type: column, center: [2, 2, 1.5], width: 0.4, height: 3, depth: 0.4}\n"
    "dynamic:\n"
    "  - {name: walker, kind: person, material: wall, speed: 1.0, path: [[-3, 0], [3, 0]]}\n"
    "paths:\n"
    "  handheld: [[-4, -4, 2.0], [4, -4]]\n"
    "  wheeled: [[-4, -3], [4, -3]]\n"
    "lighting: {ambient: 0.2}\n";

TEST(SceneExtends, InheritsEverythingAndAdds) {
  const std::string dir = Folder("inherits");
  Write(dir, "base.yaml", kBase);
  Write(dir, "crowd.yaml",
        "format_version: 1\n"
        "extends: base\n"
        "name: crowd\n"
        "materials:\n"
        "  - {name: clothes, albedo: 0.25}\n"
        "primitives:\n"
        "  - {type: box, name: crate, center: [1, 1, 0.5], size: [1, 1, 1], material: clothes}\n"
        "dynamic:\n"
        "  - {name: runner, kind: person, material: clothes, speed: 2.0, path: [[-3, 1], [3, 1]]}\n"
        "  - {name: car, kind: car, material: wall, speed: 3.0, path: [[-3, -2], [3, -2]]}\n");
  Scene base, crowd;
  ASSERT_TRUE(LoadScene(dir + "/base.yaml", &base).ok);
  const Status s = LoadScene(dir + "/crowd.yaml", &crowd);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(crowd.name, "crowd");
  EXPECT_EQ(crowd.description, "the base");  // not overridden: inherited
  EXPECT_TRUE(crowd.closed);
  EXPECT_TRUE(crowd.bounds.isApprox(base.bounds));
  EXPECT_EQ(crowd.source_path, dir + "/crowd.yaml");
  ASSERT_EQ(crowd.materials.size(), 3u);
  EXPECT_EQ(crowd.materials[2].name, "clothes");
  ASSERT_EQ(crowd.primitives.size(), 3u);
  EXPECT_EQ(crowd.primitives[0].name, "room");
  EXPECT_EQ(crowd.primitives[2].name, "crate");
  EXPECT_EQ(crowd.primitives[2].material_id, 2);
  EXPECT_EQ(crowd.elements.size(), 1u);
  ASSERT_EQ(crowd.dynamic_objects.size(), 3u);
  EXPECT_EQ(crowd.dynamic_objects[0].name, "walker");
  EXPECT_EQ(crowd.dynamic_objects[2].kind, "car");
  EXPECT_EQ(crowd.path_order, base.path_order);
  EXPECT_DOUBLE_EQ(crowd.lighting.ambient, 0.2);
  // The base's static world is the derived one's first primitives, triangle for triangle.
  const TriangleMesh mb = BuildMesh(base), mc = BuildMesh(crowd);
  ASSERT_GT(mc.triangles.size(), mb.triangles.size());
  for (std::size_t i = 0; i < mb.vertices_m.size(); ++i) EXPECT_EQ(mb.vertices_m[i], mc.vertices_m[i]);
  // The added objects move: 2 m/s and 3 m/s for 1 s along their straight paths.
  EXPECT_NEAR((DynamicObjectPose(crowd.dynamic_objects[1], 1.0).translation() -
               DynamicObjectPose(crowd.dynamic_objects[1], 0.0).translation()).norm(), 2.0, 1e-12);
  EXPECT_NEAR((DynamicObjectPose(crowd.dynamic_objects[2], 1.0).translation() -
               DynamicObjectPose(crowd.dynamic_objects[2], 0.0).translation()).norm(), 3.0, 1e-12);
}

TEST(SceneExtends, OverridesScalarsPathsMaterialsAndLighting) {
  const std::string dir = Folder("overrides");
  Write(dir, "base.yaml", kBase);
  std::filesystem::create_directories(dir + "/variants");
  Write(dir, "variants/glassy.yaml",
        "format_version: 1\n"
        "extends: ../base.yaml\n"  // relative to this file's folder, with the extension
        "name: glassy\n"
        "description: glass made transmissive\n"
        "closed: false\n"
        "bounds: {min: [-4, -4, 0], max: [4, 4, 3]}\n"
        "materials:\n"
        "  - {name: glass, albedo: 0.05, transmittance: 0.9}\n"
        "paths:\n"
        "  handheld: [[-3, -3], [3, -3], [3, 3]]\n"
        "  car: [[-3, 0], [3, 0]]\n"
        "lighting: {headlight: 0.5}\n");
  Scene s;
  const Status st = LoadScene(dir + "/variants/glassy.yaml", &s);
  ASSERT_TRUE(st.ok) << st.message;
  EXPECT_EQ(s.description, "glass made transmissive");
  EXPECT_FALSE(s.closed);
  EXPECT_DOUBLE_EQ(s.bounds.max().x(), 4.0);
  ASSERT_EQ(s.materials.size(), 2u);  // redefined in place: the base's primitives keep their material ids
  EXPECT_EQ(s.materials[1].name, "glass");
  EXPECT_DOUBLE_EQ(s.materials[1].transmittance, 0.9);
  EXPECT_EQ(s.primitives[1].material_id, 1);
  EXPECT_EQ(s.default_paths.at("handheld").size(), 3u);  // replaced, not appended
  EXPECT_EQ(s.default_paths.at("wheeled").size(), 2u);   // inherited
  EXPECT_EQ(s.path_order, (std::vector<std::string>{"handheld", "wheeled", "car"}));
  EXPECT_DOUBLE_EQ(s.lighting.headlight, 0.5);
  EXPECT_DOUBLE_EQ(s.lighting.ambient, SceneLighting{}.ambient);  // lighting replaces as a whole
}

TEST(SceneExtends, MissingBaseCyclesAndBaseErrorsNameTheFile) {
  const std::string dir = Folder("errors");
  Write(dir, "orphan.yaml", "format_version: 1\nname: orphan\nextends: nosuch\n");
  Scene s;
  Status st = LoadScene(dir + "/orphan.yaml", &s);
  ASSERT_FALSE(st.ok);
  EXPECT_NE(st.message.find(dir + "/orphan.yaml:3:"), std::string::npos) << st.message;
  EXPECT_NE(st.message.find("nosuch.yaml"), std::string::npos) << st.message;
  EXPECT_NE(st.message.find("not found"), std::string::npos) << st.message;

  Write(dir, "a.yaml", "format_version: 1\nextends: b\n");
  Write(dir, "b.yaml", "format_version: 1\nextends: a\n");
  st = LoadScene(dir + "/a.yaml", &s);
  ASSERT_FALSE(st.ok);
  EXPECT_NE(st.message.find("extends cycle"), std::string::npos) << st.message;
  EXPECT_NE(st.message.find("b.yaml:2:"), std::string::npos) << st.message;  // where the cycle closes
  Write(dir, "self.yaml", "format_version: 1\nextends: self\n");
  st = LoadScene(dir + "/self.yaml", &s);
  ASSERT_FALSE(st.ok);
  EXPECT_NE(st.message.find("extends cycle"), std::string::npos) << st.message;

  // An error inside the base names the base's file and line, behind the derived file's extends line.
  Write(dir, "broken.yaml", std::string(kBase) + "bogus_key: 1\n");
  Write(dir, "child.yaml", "format_version: 1\n\nextends: broken\n");
  st = LoadScene(dir + "/child.yaml", &s);
  ASSERT_FALSE(st.ok);
  EXPECT_NE(st.message.find(dir + "/child.yaml:3:"), std::string::npos) << st.message;
  EXPECT_NE(st.message.find(dir + "/broken.yaml:"), std::string::npos) << st.message;
  EXPECT_NE(st.message.find("bogus_key"), std::string::npos) << st.message;
}

TEST(SceneExtends, UnknownKeysDuplicatesAndBadTransmittanceAreErrors) {
  const std::string dir = Folder("strict");
  Write(dir, "base.yaml", kBase);
  const auto fails_with = [&](const std::string& body, const std::string& what) {
    Write(dir, "v.yaml", "format_version: 1\nextends: base\n" + body);
    Scene s;
    const Status st = LoadScene(dir + "/v.yaml", &s);
    EXPECT_FALSE(st.ok) << body;
    EXPECT_NE(st.message.find(dir + "/v.yaml:"), std::string::npos) << st.message;
    EXPECT_NE(st.message.find(what), std::string::npos) << st.message;
  };
  fails_with("base: base.yaml\n", "unknown key 'base'");  // not a key of the format
  fails_with("dynamic:\n  - {name: walker, kind: person, material: wall, speed: 1, path: [[0, 0], [1, 0]]}\n",
             "dynamic object 'walker' defined twice");
  fails_with("elements:\n  - {name: col, type: column, center: [0, 0, 1], width: 1, height: 1}\n",
             "element 'col' defined twice");
  fails_with("materials:\n  - {name: x, albedo: 0.5}\n  - {name: x, albedo: 0.5}\n", "material 'x' defined twice");
  fails_with("materials:\n  - {name: glass, albedo: 0.2, transmittance: 0.9}\n", "transmittance");
  // Without extends, bounds, materials and primitives stay required.
  Write(dir, "bare.yaml", "format_version: 1\nname: bare\n");
  Scene s;
  const Status st = LoadScene(dir + "/bare.yaml", &s);
  ASSERT_FALSE(st.ok);
  EXPECT_NE(st.message.find("missing required key 'bounds'"), std::string::npos) << st.message;
}

}  // namespace
}  // namespace rotolidar::sim
