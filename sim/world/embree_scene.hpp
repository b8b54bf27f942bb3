#pragma once
// Ray casting against the scene's triangles with Embree 3 (the LiDAR's geometry engine), including dynamic
// objects (people, cars) that move with time.
//
// Precision: Embree works in float; in a room-sized scene (|coordinates| < 100 m) hit distances are good to
// ~1e-5 m, far below the VLP-16's 2 mm distance unit (at 500 m from the origin: ~5e-5 m).
//
// Dynamic objects: each object's body mesh is its own Embree scene, instanced into the top-level scene with its
// pose at the current time; the static world is one more instance (identity) so that moving an object never
// rebuilds the static BVH. SetTime(t) recomputes every object's pose (scene_dynamic.hpp), updates the instance
// transforms and recommits the top level: a rebuild over (objects + 1) instances, O(N log N) in the number of
// objects and independent of the triangle count (cost: docs/scene_format.md, 'Dynamic objects'; per scene:
// `rotolidar scene list`). Call it once per VLP-16 packet (1.33 ms of firing).
// A scene without dynamic objects is one flat triangle geometry, as fast as before.
//
// Closest-point searches (the map-to-truth distance, bench/metrics/surface_distance.hpp) use the same BVH through
// VisitStaticTrianglesNear, so every Embree device and scene of the project is created here.
//
// Thread safety: after Create, Intersect, IntersectBatch and VisitStaticTrianglesNear are const and may run
// concurrently from any threads; SetTime must not run concurrently with them (call it between packets).
#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include <embree3/rtcore.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/types/time.hpp"
#include "core/util/status.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim {

/// Result of one ray.
struct RayHit {
  bool hit = false;
  double distance_m = 0.0;  ///< along the (unit) ray direction from its origin; valid when hit
  Eigen::Vector3d normal_world = Eigen::Vector3d::Zero();  ///< unit, turned to face the ray origin (n . dir <= 0)
  bool front_face = false;  ///< the ray struck the triangle's front side (mesh winding), e.g. a room wall's inside
  int material_id = -1;     ///< index into materials(); -1 when no hit
  /// -1 when no hit; the static mesh's triangle index when object_id == -1, else the index into that object's
  /// body mesh (BuildObjectMesh).
  int triangle_id = -1;
  int object_id = -1;  ///< -1: the static world (or no hit); k: Scene::dynamic_objects[k]
};

/// One ray for the batched call. `dir_world` need not be unit; it is normalised.
struct RayQuery {
  Eigen::Vector3d origin_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d dir_world = Eigen::Vector3d::UnitX();
  double t_max_m = 1e3;  ///< hits farther than this are ignored
};

/// Owns an RTCDevice and a committed RTCScene. Not copyable or movable (hand it around by reference or
/// unique_ptr). Embree errors are logged through rotolidar's logging.
class EmbreeScene {
 public:
  /// Builds the acceleration structure of a static mesh. Fails (with the triangle/vertex index named) on an
  /// empty mesh, out-of-range indices or material ids, non-finite vertices, degenerate triangles, or an Embree
  /// device/scene error.
  static Status Create(const TriangleMesh& mesh, std::unique_ptr<EmbreeScene>* out);

  /// The scene's static world (BuildMesh) plus its dynamic objects, posed at time t0. The scene must be valid.
  static Status Create(const Scene& scene, std::unique_ptr<EmbreeScene>* out, Seconds t0 = 0.0);

  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  /// Moves every dynamic object to its pose at time t and recommits (no-op without dynamic objects).
  /// Not thread-safe against Intersect/IntersectBatch.
  void SetTime(Seconds t);
  Seconds time() const { return time_s_; }
  std::size_t num_dynamic_objects() const { return objects_.size(); }
  /// T_world_body of dynamic object k at the current time.
  const Eigen::Isometry3d& object_pose(std::size_t k) const { return objects_.at(k).T_world_body; }

  /// Closest hit along origin + t * dir for t in (0, t_max_m]. `dir_world` need not be unit (it is normalised);
  /// a zero direction or non-positive t_max gives no hit.
  RayHit Intersect(const Eigen::Vector3d& origin_world, const Eigen::Vector3d& dir_world, double t_max_m) const;

  /// The same for `count` rays at once through Embree's stream API (faster for coherent batches, e.g. a firing
  /// sequence after another). hits[i] answers rays[i]; results equal Intersect's ray for ray.
  void IntersectBatch(const RayQuery* rays, std::size_t count, RayHit* hits) const;

  /// The candidates of a closest-point search around p over the static world (dynamic objects are not searched):
  /// Embree's BVH point query calls visit(triangle_id) for each static triangle whose bounding box lies within
  /// the current radius of p, starting at radius_m, in BVH order (a triangle may come more than once). visit
  /// returns the radius to go on with; returning a smaller one (the best distance so far) prunes the search.
  /// Triangle ids index the static mesh, as RayHit::triangle_id with object_id == -1.
  void VisitStaticTrianglesNear(const Eigen::Vector3d& p, double radius_m,
                                const std::function<double(int triangle_id)>& visit) const;

  const Material& material(int id) const { return materials_.at(static_cast<std::size_t>(id)); }
  const std::vector<Material>& materials() const { return materials_; }
  /// World-frame bounds of the static world's retroreflective surfaces, one box per scene primitive (or mesh
  /// triangle set without primitive ids); for the VLP-16 twin's blooming.
  const std::vector<Eigen::AlignedBox3d>& retroreflective_bounds() const { return retro_bounds_; }
  /// Static triangles plus every dynamic object's body triangles.
  std::size_t num_triangles() const;

 private:
  /// A triangle set with its per-triangle data (the static world or one object's body, in its own frame).
  struct Part {
    std::vector<Eigen::Vector3d> front_normals;  ///< per triangle, unit, by winding, in the part's frame
    std::vector<int> material_ids;
  };
  struct Object {
    DynamicObject description;
    RTCScene scene = nullptr;
    unsigned instance_id = 0;  ///< geometry id of its instance in the top-level scene
    Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
    Part part;
  };

  EmbreeScene() = default;
  Status AddTriangles(RTCScene target, const TriangleMesh& mesh, Part* part);
  Status AddObject(const Scene& scene, const DynamicObject& object);
  void FillHit(const RTCRayHit& rh, const Eigen::Vector3d& dir_unit, RayHit* out) const;

  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;          ///< what rays traverse
  RTCScene static_scene_ = nullptr;   ///< with dynamic objects: the static world, instanced with identity
  unsigned static_instance_id_ = RTC_INVALID_GEOMETRY_ID;
  Part static_part_;
  std::vector<Object> objects_;
  std::vector<int> object_of_instance_;  ///< top-level geometry id -> object index (-1: the static world)
  std::vector<Material> materials_;
  std::vector<Eigen::AlignedBox3d> retro_bounds_;
  Seconds time_s_ = 0.0;
};

}  // namespace rotolidar::sim
