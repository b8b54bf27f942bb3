// The MuJoCo model generated from a Scene has the same surfaces as the Embree geometry built from it (mj_ray vs
// Embree on random rays, static and dynamic), and the offscreen renderer's depth agrees with Embree ranges.
#include <cmath>
#include <cstring>
#include <iostream>

#include <gtest/gtest.h>

#include "sim/world/offscreen_render.hpp"
#include "sim/world/scene_dynamic.hpp"
#include "sim/world/scene_mujoco.hpp"
#include "tests/sim/world/world_fixtures.hpp"

namespace rotolidar::sim {
namespace {

using testing::SceneNames;
using testing::ScenePath;

/// Compares mj_ray and Embree on `n` random rays from inside the bounds (downwards or level in open scenes, so
/// that they hit). Embree intersects in float, MuJoCo in double: measured worst |difference| 5e-6 m (box_room)
/// to 2.7e-5 m (urban_loop, coordinates up to ~200 m); the bound 2e-4 m (growing past 100 m) leaves 7x margin.
/// Rays that graze an edge within the rounding could hit on one side and miss on the other: at most 0.1 % of
/// the rays may disagree that way (measured: none).
void ExpectAgreement(const Scene& scene, const EmbreeScene& es, const MujocoScene& ms, const std::string& name,
                     int n, uint64_t seed) {
  RandomStream rng(seed, "test.mujoco." + name);
  int disagreements = 0, hits = 0;
  double worst_m = 0.0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d o = testing::RandomInside(scene.bounds, 0.05, &rng);
    Eigen::Vector3d d = testing::RandomUnit(&rng);
    if (!scene.closed) d.z() = -std::abs(d.z());  // open scenes: no rays into the empty sky
    const RayHit e = es.Intersect(o, d, 1e4);
    int geom = -1;
    const double m = ms.Ray(o, d, &geom);
    const double tol_m = 2e-4 * std::max(1.0, e.distance_m / 100.0);
    if (e.hit != (m >= 0.0) || (e.hit && std::abs(e.distance_m - m) > tol_m)) {
      ++disagreements;
      ADD_FAILURE_AT(__FILE__, __LINE__) << name << " ray " << i << " from " << o.transpose() << " dir "
                                         << d.transpose() << ": embree " << (e.hit ? e.distance_m : -1.0)
                                         << " mujoco " << m << " (geom " << geom << ")";
      continue;
    }
    if (e.hit) worst_m = std::max(worst_m, std::abs(e.distance_m - m));
    hits += e.hit;
  }
  EXPECT_LE(disagreements, n / 1000) << name;
  // The comparison needs surfaces to compare: >= 98 % of the rays hit in the hand-made scenes; in urban_loop
  // ~80 % (origins below its sloping ground see nothing).
  EXPECT_GT(hits, n * 3 / 4) << name;
  std::cout << name << ": " << hits << " of " << n << " rays hit, worst |embree - mujoco| " << worst_m << " m\n";
}

TEST(SceneMujoco, EveryScenesMujocoModelHasTheEmbreeSurfaces) {
  for (const std::string& name : SceneNames()) {
    Scene scene;
    ASSERT_TRUE(LoadScene(ScenePath(name), &scene).ok);
    std::unique_ptr<MujocoScene> ms;
    const Status s = MujocoScene::Create(scene, &ms);
    ASSERT_TRUE(s.ok) << name << ": " << s.message;
    std::unique_ptr<EmbreeScene> es;
    ASSERT_TRUE(EmbreeScene::Create(scene, &es).ok);
    ExpectAgreement(scene, *es, *ms, name, name == "urban_loop" ? 600 : 1500, 5);
  }
}

TEST(SceneMujoco, GeomsMapBackToPrimitivesWithTheDocumentedGroups) {
  Scene scene;
  ASSERT_TRUE(LoadScene(testing::BoxRoomPath(), &scene).ok);
  std::unique_ptr<MujocoScene> ms;
  ASSERT_TRUE(MujocoScene::Create(scene, &ms).ok);
  const mjModel* m = ms->model();
  // 8 boxes x 12 planes (6 faces, front and back) + 3 quads x 2 planes + 2 cylinder meshes.
  ASSERT_EQ(m->ngeom, 8 * 12 + 3 * 2 + 2);
  int ceilings = 0, backs = 0;
  for (int g = 0; g < m->ngeom; ++g) {
    const GeomSource& src = ms->geom_sources()[static_cast<std::size_t>(g)];
    ASSERT_GE(src.primitive, 0);
    const Primitive& p = scene.primitives[static_cast<std::size_t>(src.primitive)];
    EXPECT_EQ(m->geom_type[g], p.type == PrimitiveType::kCylinder ? mjGEOM_MESH : mjGEOM_PLANE);
    ceilings += m->geom_group[g] == kGeomGroupCeiling;
    backs += m->geom_group[g] == kGeomGroupBackside;
    EXPECT_EQ(m->geom_contype[g], 0);
  }
  EXPECT_EQ(ceilings, 1);   // the room's +z face
  EXPECT_EQ(backs, 8 * 6);  // box faces' back sides (quads keep theirs visible)
}

TEST(SceneMujoco, DynamicObjectsMoveTheSameInBothEngines) {
  Scene scene;
  ASSERT_TRUE(LoadScene(ScenePath("parking"), &scene).ok);
  std::unique_ptr<MujocoScene> ms;
  ASSERT_TRUE(MujocoScene::Create(scene, &ms).ok);
  std::unique_ptr<EmbreeScene> es;
  ASSERT_TRUE(EmbreeScene::Create(scene, &es).ok);
  for (double t : {0.0, 9.5, 31.25}) {
    es->SetTime(t);
    ms->SetTime(t);
    for (std::size_t k = 0; k < scene.dynamic_objects.size(); ++k) {
      const Eigen::Isometry3d T = DynamicObjectPose(scene.dynamic_objects[k], t);
      EXPECT_TRUE(es->object_pose(k).isApprox(T, 1e-12));
      // Straight down onto the body's centre from 0.5 m above its top (people's heads, cars' roofs).
      const double top_m = BuildObjectMesh(scene, scene.dynamic_objects[k]).Bounds().max().z();
      const Eigen::Vector3d origin = T * Eigen::Vector3d(0, 0, top_m + 0.5);
      const Eigen::Vector3d dir = -Eigen::Vector3d::UnitZ();
      const RayHit e = es->Intersect(origin, dir, 100.0);
      ASSERT_TRUE(e.hit) << scene.dynamic_objects[k].name << " t " << t;
      EXPECT_NEAR(e.distance_m, 0.5, 1e-4) << scene.dynamic_objects[k].name;
      EXPECT_EQ(e.object_id, static_cast<int>(k)) << scene.dynamic_objects[k].name << " t " << t;
      int geom = -1;
      EXPECT_NEAR(ms->Ray(origin, dir, &geom), e.distance_m, 2e-4) << scene.dynamic_objects[k].name;
      ASSERT_GE(geom, 0);
      EXPECT_EQ(ms->geom_sources()[static_cast<std::size_t>(geom)].object, static_cast<int>(k));
    }
  }
  std::unique_ptr<EmbreeScene> es_static;
  ASSERT_TRUE(EmbreeScene::Create(scene, &es_static, 31.25).ok);  // the same t given at creation
  ExpectAgreement(scene, *es_static, *ms, "parking_t31", 1000, 9);
}

TEST(SceneMujoco, OffscreenDepthMatchesEmbreeRanges) {
  Scene scene;
  ASSERT_TRUE(LoadScene(ScenePath("lab"), &scene).ok);
  std::unique_ptr<MujocoScene> ms;
  ASSERT_TRUE(MujocoScene::Create(scene, &ms).ok);
  std::unique_ptr<EmbreeScene> es;
  ASSERT_TRUE(EmbreeScene::Create(scene, &es).ok);
  CameraIntrinsics k;
  k.width_px = 160;
  k.height_px = 120;
  k.fx_px = k.fy_px = 100.0;
  k.cx_px = 83.0;  // off-centre principal point: checks the frustum shift
  k.cy_px = 57.5;
  std::unique_ptr<OffscreenRenderer> renderer;
  const Status created = OffscreenRenderer::Create(ms->model(), k.width_px, k.height_px, 0, &renderer);
  ASSERT_TRUE(created.ok) << created.message;
  const Eigen::Isometry3d T_world_cam = LookAt(Eigen::Vector3d(1.0, 1.2, 1.5), Eigen::Vector3d(14.0, 5.0, 1.0));
  RenderSettings settings;
  settings.near_m = 0.05;
  settings.far_m = 100.0;
  RgbImage rgb;
  std::vector<float> depth;
  const Status s = renderer->Render(ms->model(), ms->data(), T_world_cam, k, settings, &rgb, &depth);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_EQ(rgb.rgb.size(), 160u * 120u * 3u);
  double sum = 0.0, sum2 = 0.0;
  for (uint8_t v : rgb.rgb) sum += v, sum2 += double(v) * v;
  const double mean = sum / rgb.rgb.size();
  EXPECT_GT(std::sqrt(sum2 / rgb.rgb.size() - mean * mean), 10.0);  // a picture, not a blank
  // Pixel centres (u + 0.5, v + 0.5): the camera ray's Embree range times its cos to the axis is the depth.
  int compared = 0, outliers = 0;
  for (int v = 2; v < k.height_px; v += 6) {
    for (int u = 2; u < k.width_px; u += 6) {
      const Eigen::Vector3d ray_cam((u + 0.5 - k.cx_px) / k.fx_px, (v + 0.5 - k.cy_px) / k.fy_px, 1.0);
      const RayHit hit = es->Intersect(T_world_cam.translation(), T_world_cam.linear() * ray_cam, 100.0);
      ASSERT_TRUE(hit.hit);
      const double z_m = hit.distance_m / ray_cam.norm();
      const double rendered = depth[static_cast<std::size_t>(v * k.width_px + u)];
      ++compared;
      // 24-bit depth at <= 16 m with near 0.05 m: ~1e-3 m resolution. Pixels on a silhouette may see the
      // other surface (the rasteriser's sample and the ray differ by float rounding): allowed up to 2 %.
      if (std::abs(rendered - z_m) > 0.01 + 0.002 * z_m) ++outliers;
    }
  }
  EXPECT_GT(compared, 400);
  EXPECT_LE(outliers, compared / 50) << outliers << " of " << compared;
}

TEST(SceneMujoco, RendererRejectsBadIntrinsics) {
  Scene scene = testing::PlainRoom();
  std::unique_ptr<MujocoScene> ms;
  ASSERT_TRUE(MujocoScene::Create(scene, &ms).ok);
  std::unique_ptr<OffscreenRenderer> renderer;
  ASSERT_TRUE(OffscreenRenderer::Create(ms->model(), 64, 48, 0, &renderer).ok);
  CameraIntrinsics k;
  k.width_px = 64;
  k.height_px = 48;
  k.fx_px = 50.0;
  k.fy_px = 60.0;  // non-square pixels: MuJoCo's frustum cannot do them
  RgbImage rgb;
  Status s = renderer->Render(ms->model(), ms->data(), Eigen::Isometry3d::Identity(), k, RenderSettings(), &rgb);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("fx_px"), std::string::npos) << s.message;
  k.fy_px = 50.0;
  k.width_px = 65;  // larger than the maxima
  s = renderer->Render(ms->model(), ms->data(), Eigen::Isometry3d::Identity(), k, RenderSettings(), &rgb);
  EXPECT_FALSE(s.ok);
}

TEST(SceneMujoco, TexturesAreDeterministicAndFilled) {
  for (const TextureSpec& spec : BuiltinTextures()) {
    std::string error;
    ASSERT_TRUE(spec.Validate(&error)) << error;
    const RgbImage a = RenderTexture(spec), b = RenderTexture(spec);
    EXPECT_EQ(a.rgb, b.rgb) << spec.name;
    ASSERT_EQ(a.rgb.size(), static_cast<std::size_t>(3 * spec.resolution_px * spec.resolution_px));
  }
  Scene scene;
  ASSERT_TRUE(LoadScene(testing::BoxRoomPath(), &scene).ok);
  std::unique_ptr<MujocoScene> ms;
  ASSERT_TRUE(MujocoScene::Create(scene, &ms).ok);
  const mjModel* m = ms->model();
  const int id = mj_name2id(m, mjOBJ_TEXTURE, "tex_wood_floor");
  ASSERT_GE(id, 0);
  const RgbImage wood = RenderTexture(*FindTexture({}, "wood_floor"));
  EXPECT_EQ(0, std::memcmp(m->tex_rgb + m->tex_adr[id], wood.rgb.data(), wood.rgb.size()));
}

}  // namespace
}  // namespace rotolidar::sim
