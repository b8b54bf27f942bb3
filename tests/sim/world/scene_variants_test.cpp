// The harder scenes (docs/scenes.md, 'Harder scenes'): the crowd variants extend their base scene without
// changing it, their added people and cars are there and move, and none of them rides along the rig's default
// path; the park's foliage and the atrium's glass are declared transmissive and the crowns are porous; the
// tunnel shows nothing that faces along its axis from the middle.
#include <cmath>
#include <cstring>
#include <iostream>

#include <gtest/gtest.h>

#include "sim/rig/carrier_paths.hpp"
#include "sim/scene_carrier.hpp"
#include "sim/world/scene_dynamic.hpp"
#include "tests/sim/world/world_fixtures.hpp"
#include "core/util/log.hpp"

namespace rotolidar::sim {
namespace {

using testing::ScenePath;

Scene Load(const std::string& name) {
  Scene scene;
  const Status s = LoadScene(ScenePath(name), &scene);
  ROTOLIDAR_CHECK(s.ok, s.message);
  return scene;
}

int Count(const std::vector<DynamicObject>& objects, std::size_t from, const std::string& kind) {
  int n = 0;
  for (std::size_t i = from; i < objects.size(); ++i) n += objects[i].kind == kind;
  return n;
}

struct Variant {
  const char* name;
  const char* base;
  int min_people;  ///< added
  int min_cars;    ///< added
};

const Variant kVariants[] = {{"corridor_busy", "corridor", 13, 0},
                             {"lab_people", "lab", 5, 0},
                             {"parking_traffic", "parking", 5, 4},
                             {"urban_loop_traffic", "urban_loop", 7, 12}};

TEST(SceneVariants, CrowdVariantsKeepTheirBaseAndAddMovingPeopleAndCars) {
  for (const Variant& v : kVariants) {
    const Scene base = Load(v.base), scene = Load(v.name);
    // The static world is the base's, byte for byte.
    const TriangleMesh mb = BuildMesh(base), ms = BuildMesh(scene);
    ASSERT_EQ(mb.vertices_m.size(), ms.vertices_m.size()) << v.name;
    EXPECT_EQ(0, std::memcmp(mb.vertices_m.data(), ms.vertices_m.data(), mb.vertices_m.size() * 3 * sizeof(double)))
        << v.name;
    EXPECT_EQ(mb.material_ids, ms.material_ids) << v.name;
    EXPECT_EQ(scene.elements.size(), base.elements.size()) << v.name;
    EXPECT_EQ(scene.default_paths.size(), base.default_paths.size()) << v.name;
    // The base's objects come first and move as before; the added ones are there.
    const std::size_t n0 = base.dynamic_objects.size();
    ASSERT_GT(scene.dynamic_objects.size(), n0) << v.name;
    for (std::size_t i = 0; i < n0; ++i) {
      EXPECT_EQ(scene.dynamic_objects[i].name, base.dynamic_objects[i].name) << v.name;
      EXPECT_TRUE(DynamicObjectPose(scene.dynamic_objects[i], 7.3).isApprox(
          DynamicObjectPose(base.dynamic_objects[i], 7.3), 1e-12)) << v.name;
    }
    EXPECT_GE(Count(scene.dynamic_objects, n0, "person"), v.min_people) << v.name;
    EXPECT_GE(Count(scene.dynamic_objects, n0, "car"), v.min_cars) << v.name;
  }
}

/// Every object of every new scene moves: over 3 s its positions (every 0.5 s) spread at least speed x 1 s
/// (a back-and-forth object turns at most once in 3 s on these paths, all longer than 4.5 m, so one side of
/// the turn lasts >= 1.5 s).
TEST(SceneVariants, EveryAddedObjectMoves) {
  int objects = 0;
  for (const char* name : {"corridor_busy", "lab_people", "parking_traffic", "urban_loop_traffic", "park",
                           "glass_atrium", "tunnel"}) {
    const Scene scene = Load(name);
    for (const DynamicObject& o : scene.dynamic_objects) {
      ASSERT_GT(PathLength(o), 1.5 * o.speed_mps) << name << "/" << o.name;
      double spread = 0.0;
      for (double a = 0.0; a <= 3.0; a += 0.5) {
        for (double b = a + 0.5; b <= 3.0; b += 0.5) {
          spread = std::max(spread, (DynamicObjectPose(o, a).translation() - DynamicObjectPose(o, b).translation())
                                        .head<2>().norm());
        }
      }
      EXPECT_GE(spread, o.speed_mps * 1.0 - 1e-9) << name << "/" << o.name;
      ++objects;
    }
  }
  EXPECT_GE(objects, 60);
}

/// No person or car stays on the rig: along each new scene's default carrier path (its target motion, sampled
/// every 0.1 s for 120 s), the share of time any object's body centre is within 0.6 m of the rig's base
/// (horizontally) stays small. Crossing the path costs ~1 s near the rig; riding along would cost all of it.
TEST(SceneVariants, NoObjectRidesAlongTheRigsDefaultPath) {
  for (const char* name : {"corridor_busy", "lab_people", "parking_traffic", "urban_loop_traffic", "park",
                           "glass_atrium", "tunnel"}) {
    const Scene scene = Load(name);
    CarrierConfig carrier;
    ChooseSceneCarrier(scene, &carrier);
    ASSERT_TRUE(FillScenePath(scene, &carrier).ok) << name;
    std::unique_ptr<BaseMotion> motion;
    const Status s = MakeCarrierMotion(carrier, &motion);
    ASSERT_TRUE(s.ok) << name << ": " << s.message;
    const int samples = 1200;
    double worst = 0.0;
    std::string worst_name = "none";
    for (const DynamicObject& o : scene.dynamic_objects) {
      int near = 0;
      for (int k = 0; k < samples; ++k) {
        const double t = 0.1 * k;
        const Eigen::Vector3d rig = motion->At(t).T_world_base.translation();
        near += (DynamicObjectPose(o, t).translation() - rig).head<2>().norm() < 0.6;
      }
      const double share = double(near) / samples;
      if (share > worst) worst = share, worst_name = o.name;
    }
    std::cout << name << ": worst " << worst_name << " near the rig " << 100.0 * worst << " % of 120 s\n";
    // 3 % = 3.6 s of 120 s (measured worst: printed above, docs/scenes.md 'Harder scenes').
    EXPECT_LT(worst, 0.03) << name << ": " << worst_name << " is near the rig " << 100.0 * worst << " % of the time";
  }
}

TEST(SceneVariants, FoliageAndGlassAreTransmissiveAndCrownsPorous) {
  const Scene park = Load("park");
  const Material& foliage = park.materials.at(static_cast<std::size_t>(park.FindMaterial("foliage")));
  EXPECT_GT(foliage.transmittance, 0.0);
  const Scene atrium = Load("glass_atrium");
  const Material& glass = atrium.materials.at(static_cast<std::size_t>(atrium.FindMaterial("glass")));
  EXPECT_GE(glass.transmittance, 0.8);
  EXPECT_GE(atrium.FindMaterial("mirror"), 0);
  // Geometric porosity: horizontal rays through the middle of a crown (|dy| < 0.8 m, |z - 4.1| < 1 m) of the
  // park's tree at (-20, -12), towards -x from 4 m east of it (the neighbouring crowns are 8 m away).
  // make_meshes.py's ray cast of the same region: 67 % hit a leaf (measured here: 1,343 of 2,000).
  const std::unique_ptr<EmbreeScene> es = testing::MakeEmbree(park);
  RandomStream rng(5, "test.crown");
  int hits = 0, n = 2000;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d o{-16.0, -12.0 + (1.6 * rng.Uniform() - 0.8), 4.1 + (2.0 * rng.Uniform() - 1.0)};
    const RayHit hit = es->Intersect(o, -Eigen::Vector3d::UnitX(), 7.0);  // stops before the next crown
    hits += hit.hit;
  }
  std::cout << "park crown: " << hits << " of " << n << " rays hit a leaf\n";
  EXPECT_GT(double(hits) / n, 0.5);
  EXPECT_LT(double(hits) / n, 0.85);
}

/// From the middle of the tunnel (its default paths' start), nothing within the VLP-16's 100 m faces along
/// the axis: of 20,000 random rays, those that hit a surface whose normal has |x| > 0.5 (only the small ends of
/// the lights, the extinguisher cabinet and door-leaf edges could) are measured 0; 10 allowed.
TEST(SceneVariants, TheTunnelShowsAlmostNothingAlongItsAxis) {
  const Scene tunnel = Load("tunnel");
  const std::unique_ptr<EmbreeScene> es = testing::MakeEmbree(tunnel);
  const auto& path = tunnel.default_paths.at("handheld");
  const Eigen::Vector3d o(path.front().x_m, path.front().y_m, 1.5);
  RandomStream rng(6, "test.tunnel");
  int axial = 0, hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const RayHit hit = es->Intersect(o, testing::RandomUnit(&rng), 100.0);
    hits += hit.hit;
    axial += hit.hit && std::abs(hit.normal_world.x()) > 0.5;
  }
  std::cout << "tunnel: " << hits << " of 20000 rays hit within 100 m, " << axial << " on axis-facing surfaces\n";
  EXPECT_GT(hits, 19900);  // closed, but rays along the axis run out of range (measured 19,997 hit)
  EXPECT_LT(axial, 10);
}

}  // namespace
}  // namespace rotolidar::sim
