// Point-to-mesh distance over sim::EmbreeScene's BVH (contract in surface_distance.hpp).
#include "bench/metrics/surface_distance.hpp"

#include "sim/world/embree_scene.hpp"

namespace rotolidar::bench {

Eigen::Vector3d ClosestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c) {
  // Voronoi regions of the vertices, edges and face in turn.
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = va + vb + vc;
  if (denom <= 0) return a;  // degenerate triangle: any vertex
  return a + ab * (vb / denom) + ac * (vc / denom);
}

SurfaceDistance::SurfaceDistance() = default;
SurfaceDistance::~SurfaceDistance() = default;

Status SurfaceDistance::Create(const sim::TriangleMesh& mesh, std::unique_ptr<SurfaceDistance>* out) {
  if (mesh.triangles.empty()) return Status::Error("surface distance: the mesh has no triangles");
  std::unique_ptr<SurfaceDistance> s(new SurfaceDistance());
  if (Status st = sim::EmbreeScene::Create(mesh, &s->bvh_); !st)
    return Status::Error("surface distance: " + st.message);
  s->vertices_m_ = mesh.vertices_m;
  s->triangles_ = mesh.triangles;
  *out = std::move(s);
  return Status::Ok();
}

double SurfaceDistance::Distance(const Eigen::Vector3d& p, double max_distance_m, int* triangle_id) const {
  double best_distance = max_distance_m;
  int best_triangle = -1;
  // Each candidate's exact distance; the search radius shrinks to the best one so far.
  bvh_->VisitStaticTrianglesNear(p, max_distance_m, [&](int id) {
    const Eigen::Vector3i& t = triangles_[static_cast<size_t>(id)];
    const double d = (ClosestPointOnTriangle(p, vertices_m_[t[0]], vertices_m_[t[1]], vertices_m_[t[2]]) - p).norm();
    if (d < best_distance) best_distance = d, best_triangle = id;
    return best_distance;
  });
  if (triangle_id) *triangle_id = best_triangle;
  return best_distance;
}

}  // namespace rotolidar::bench
