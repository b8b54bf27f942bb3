#include "bench/metrics/surface_distance.hpp"

#include <limits>

namespace rotolidar::bench {
namespace {

struct QueryState {
  const std::vector<Eigen::Vector3d>* vertices;
  const std::vector<Eigen::Vector3i>* triangles;
  Eigen::Vector3d p;
  double best_distance;
  int best_triangle;
};

bool PointQueryCallback(RTCPointQueryFunctionArguments* args) {
  auto* state = static_cast<QueryState*>(args->userPtr);
  const Eigen::Vector3i& t = (*state->triangles)[args->primID];
  const auto& v = *state->vertices;
  const double d = (ClosestPointOnTriangle(state->p, v[t[0]], v[t[1]], v[t[2]]) - state->p).norm();
  if (d >= state->best_distance) return false;
  state->best_distance = d;
  state->best_triangle = static_cast<int>(args->primID);
  args->query->radius = static_cast<float>(d);
  return true;
}

}  // namespace

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

Status SurfaceDistance::Create(const sim::TriangleMesh& mesh, std::unique_ptr<SurfaceDistance>* out) {
  if (mesh.triangles.empty()) return Status::Error("surface distance: the mesh has no triangles");
  std::unique_ptr<SurfaceDistance> s(new SurfaceDistance());
  s->vertices_m_ = mesh.vertices_m;
  s->triangles_ = mesh.triangles;
  s->device_ = rtcNewDevice(nullptr);
  if (!s->device_) return Status::Error("surface distance: rtcNewDevice failed");
  s->scene_ = rtcNewScene(s->device_);
  RTCGeometry geom = rtcNewGeometry(s->device_, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                         3 * sizeof(float), mesh.vertices_m.size()));
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                            3 * sizeof(unsigned), mesh.triangles.size()));
  if (!vb || !ib) {
    rtcReleaseGeometry(geom);
    return Status::Error("surface distance: Embree buffer allocation failed");
  }
  for (size_t i = 0; i < mesh.vertices_m.size(); ++i)
    for (int k = 0; k < 3; ++k) vb[3 * i + k] = static_cast<float>(mesh.vertices_m[i][k]);
  for (size_t i = 0; i < mesh.triangles.size(); ++i)
    for (int k = 0; k < 3; ++k) ib[3 * i + k] = static_cast<unsigned>(mesh.triangles[i][k]);
  rtcCommitGeometry(geom);
  rtcAttachGeometry(s->scene_, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(s->scene_);
  if (rtcGetDeviceError(s->device_) != RTC_ERROR_NONE) return Status::Error("surface distance: Embree build failed");
  *out = std::move(s);
  return Status::Ok();
}

SurfaceDistance::~SurfaceDistance() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

double SurfaceDistance::Distance(const Eigen::Vector3d& p, double max_distance_m, int* triangle_id) const {
  QueryState state{&vertices_m_, &triangles_, p, max_distance_m, -1};
  RTCPointQuery query;
  query.x = static_cast<float>(p.x());
  query.y = static_cast<float>(p.y());
  query.z = static_cast<float>(p.z());
  query.time = 0.0f;
  query.radius = static_cast<float>(max_distance_m);
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(scene_, &query, &context, PointQueryCallback, &state);
  if (triangle_id) *triangle_id = state.best_triangle;
  return state.best_distance;
}

}  // namespace rotolidar::bench
