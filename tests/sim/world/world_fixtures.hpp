#pragma once
// Small scenes and helpers for the world/caster tests (and the caster benchmark).
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/util/rng.hpp"
#include "sim/world/embree_scene.hpp"
#include "sim/world/scene.hpp"
#include "core/util/log.hpp"

namespace rotolidar::sim::testing {

inline std::string ScenePath(const std::string& name) {
  return std::string(ROTOLIDAR_SOURCE_DIR) + "/scenes/" + name + ".yaml";
}

inline std::string BoxRoomPath() { return ScenePath("box_room"); }

/// Every scene shipped in scenes/ (a test checks the folder holds exactly these).
inline const std::vector<std::string>& SceneNames() {
  static const std::vector<std::string> kNames = {
      "box_room", "clean_street", "corridor",        "corridor_busy", "garage",     "glass_atrium",
      "lab",      "lab_people",   "park",            "parking",       "parking_traffic", "tunnel",
      "urban_loop", "urban_loop_traffic"};
  return kNames;
}

/// An empty closed room: inner faces of a 10 x 8 x 3 m box, floor at z = 0; walls albedo 0.8, floor 0.3.
inline Scene PlainRoom() {
  Scene scene;
  scene.name = "plain_room";
  scene.closed = true;
  scene.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-5, -4, 0), Eigen::Vector3d(5, 4, 3));
  scene.materials = {Material{"wall", 0.8, false, ""}, Material{"floor", 0.3, false, ""}};
  Primitive room = MakeRoom("room", Eigen::Vector3d(0, 0, 1.5), Eigen::Vector3d(10, 8, 3), 0);
  room.floor_material_id = 1;
  scene.primitives = {room};
  return scene;
}

/// A 400 x 400 m floor quad at z = 0 (albedo 0.8), nothing else: rays that miss it escape.
inline Scene BigFloor() {
  Scene scene;
  scene.name = "big_floor";
  scene.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-100, -100, 0), Eigen::Vector3d(100, 100, 10));
  scene.materials = {Material{"floor", 0.8, false, ""}};
  Primitive floor;
  floor.type = PrimitiveType::kQuad;
  floor.name = "floor";
  floor.size_m = Eigen::Vector3d(400, 400, 0);
  scene.primitives = {floor};
  return scene;
}

/// PlainRoom with one "car" (a 2 x 1 x 1.48 m box, z 0.01..1.49) driving a 6 x 4 m rectangle at 2 m/s.
inline Scene RoomWithCar() {
  Scene scene = PlainRoom();
  scene.name = "room_with_car";
  DynamicObject car;
  car.name = "car";
  car.kind = "car";
  car.parts = {};
  Primitive body;
  body.name = "body";
  body.center_m = Eigen::Vector3d(0, 0, 0.75);
  body.size_m = Eigen::Vector3d(2.0, 1.0, 1.48);  // 1 cm above the floor: no face coplanar with it
  car.parts.push_back(body);
  car.path_m = {Eigen::Vector3d(-3, -2, 0), Eigen::Vector3d(3, -2, 0), Eigen::Vector3d(3, 2, 0),
                Eigen::Vector3d(-3, 2, 0)};
  car.speed_mps = 2.0;
  scene.dynamic_objects = {car};
  return scene;
}

inline std::unique_ptr<EmbreeScene> MakeEmbree(const Scene& scene) {
  std::unique_ptr<EmbreeScene> es;
  const Status s = EmbreeScene::Create(BuildMesh(scene), &es);
  ROTOLIDAR_CHECK(s.ok, s.message);
  return es;
}

inline Eigen::Vector3d RandomUnit(RandomStream* rng) {
  const Eigen::Vector3d v{rng->Normal(), rng->Normal(), rng->Normal()};
  return v.normalized();
}

inline Eigen::Vector3d RandomInside(const Eigen::AlignedBox3d& box, double margin_m, RandomStream* rng) {
  const Eigen::Vector3d lo = box.min().array() + margin_m, hi = box.max().array() - margin_m;
  return lo + (hi - lo).cwiseProduct(Eigen::Vector3d{rng->Uniform(), rng->Uniform(), rng->Uniform()});
}

/// Height of the lowest surface at (x, y): an upward ray from 1 m below the scene's bounds (the floor or the
/// ground; nothing lies under them). NaN when the ray hits nothing.
inline double GroundZ(const EmbreeScene& es, const Scene& scene, double x, double y) {
  const double z0 = scene.bounds.min().z() - 1.0;
  const RayHit hit = es.Intersect(Eigen::Vector3d(x, y, z0), Eigen::Vector3d::UnitZ(), 1e3);
  return hit.hit ? z0 + hit.distance_m : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace rotolidar::sim::testing
