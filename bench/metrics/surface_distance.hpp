#pragma once
// Exact distance from points to a triangle mesh: a closest-point search over the mesh's BVH (sim::EmbreeScene's
// VisitStaticTrianglesNear, the sim's Embree wrapper) with an exact point-triangle distance (Ericson, Real-Time
// Collision Detection, 5.1.5). No Embree type appears here.
// Precision: Embree stores vertices as float, so distances are good to ~1e-6 m in a room-sized scene.
// Thread safety: after Create, Distance is const and may run concurrently.
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "core/util/status.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim {
class EmbreeScene;
}  // namespace rotolidar::sim

namespace rotolidar::bench {

/// Closest point on triangle (a, b, c) to p.
Eigen::Vector3d ClosestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c);

class SurfaceDistance {
 public:
  /// Builds the BVH of `mesh` (copied). Fails on an empty mesh, on a mesh sim::EmbreeScene refuses (bad indices
  /// or material ids, non-finite vertices, degenerate triangles) or on an Embree error.
  static Status Create(const sim::TriangleMesh& mesh, std::unique_ptr<SurfaceDistance>* out);
  ~SurfaceDistance();
  SurfaceDistance(const SurfaceDistance&) = delete;
  SurfaceDistance& operator=(const SurfaceDistance&) = delete;

  /// Distance [m] from p [mesh frame] to the nearest triangle; max_distance_m when none is closer than that.
  double Distance(const Eigen::Vector3d& p, double max_distance_m = 1e3, int* triangle_id = nullptr) const;

 private:
  SurfaceDistance();
  std::unique_ptr<sim::EmbreeScene> bvh_;  ///< the mesh's static triangles, for the closest-point search
  std::vector<Eigen::Vector3d> vertices_m_;
  std::vector<Eigen::Vector3i> triangles_;
};

}  // namespace rotolidar::bench
