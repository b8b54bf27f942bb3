#pragma once
// Ray casting against the scene's triangle mesh with Embree 3 (the LiDAR's geometry engine).
//
// Precision: Embree works in float; in a room-sized scene (|coordinates| < 100 m) hit distances are good to
// ~1e-5 m, far below the VLP-16's 2 mm distance unit.
// Thread safety: after Create, Intersect and IntersectBatch are const and may run concurrently from any threads.
#include <cstddef>
#include <memory>
#include <vector>

#include <embree3/rtcore.h>
#include <Eigen/Core>

#include "core/util/log.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim {

/// Result of one ray.
struct RayHit {
  bool hit = false;
  double distance_m = 0.0;  ///< along the (unit) ray direction from its origin; valid when hit
  Eigen::Vector3d normal_world = Eigen::Vector3d::Zero();  ///< unit, turned to face the ray origin (n . dir <= 0)
  bool front_face = false;  ///< the ray struck the triangle's front side (mesh winding), e.g. a room wall's inside
  int material_id = -1;     ///< index into materials(); -1 when no hit
  int triangle_id = -1;     ///< index into the mesh's triangles; -1 when no hit
};

/// One ray for the batched call. `dir_world` need not be unit; it is normalised.
struct RayQuery {
  Eigen::Vector3d origin_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d dir_world = Eigen::Vector3d::UnitX();
  double t_max_m = 1e3;  ///< hits farther than this are ignored
};

/// Owns an RTCDevice and a committed RTCScene built from one TriangleMesh. Not copyable or movable
/// (hand it around by reference or unique_ptr). Embree errors are logged through rotolidar's logging.
class EmbreeScene {
 public:
  /// Builds the acceleration structure. Fails (with the triangle/vertex index named) on an empty mesh,
  /// out-of-range indices or material ids, non-finite vertices, or an Embree device/scene error.
  static Status Create(const TriangleMesh& mesh, std::unique_ptr<EmbreeScene>* out);

  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  /// Closest hit along origin + t * dir for t in (0, t_max_m]. `dir_world` need not be unit (it is normalised);
  /// a zero direction or non-positive t_max gives no hit.
  RayHit Intersect(const Eigen::Vector3d& origin_world, const Eigen::Vector3d& dir_world, double t_max_m) const;

  /// The same for `count` rays at once through Embree's stream API (faster for coherent batches, e.g. a firing
  /// sequence after another). hits[i] answers rays[i]; results equal Intersect's ray for ray.
  void IntersectBatch(const RayQuery* rays, std::size_t count, RayHit* hits) const;

  const Material& material(int id) const { return materials_.at(static_cast<std::size_t>(id)); }
  const std::vector<Material>& materials() const { return materials_; }
  std::size_t num_triangles() const { return front_normals_.size(); }

 private:
  EmbreeScene() = default;
  void FillHit(const RTCRayHit& rh, const Eigen::Vector3d& dir_unit, RayHit* out) const;

  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::vector<Eigen::Vector3d> front_normals_;  ///< per triangle, unit, by winding
  std::vector<int> material_ids_;
  std::vector<Material> materials_;
};

}  // namespace rotolidar::sim
