#pragma once
// Small scenes for the world/caster tests (and the caster benchmark).
#include <memory>
#include <string>

#include "sim/world/embree_scene.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim::testing {

inline std::string BoxRoomPath() { return std::string(ROTOLIDAR_SOURCE_DIR) + "/scenes/box_room.yaml"; }

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

inline std::unique_ptr<EmbreeScene> MakeEmbree(const Scene& scene) {
  std::unique_ptr<EmbreeScene> es;
  const Status s = EmbreeScene::Create(BuildMesh(scene), &es);
  ROTOLIDAR_CHECK(s.ok, s.message);
  return es;
}

}  // namespace rotolidar::sim::testing
