// Embree 3 scene: one triangle geometry for the whole mesh, robust traversal (no leaks along shared edges).
#include "sim/world/embree_scene.hpp"

#include <limits>
#include <sstream>

namespace rotolidar::sim {
namespace {

void EmbreeErrorToLog(void* /*user*/, RTCError code, const char* message) {
  LOG_ERROR("embree error " << static_cast<int>(code) << ": " << (message ? message : "(no message)"));
}

Status CheckMesh(const TriangleMesh& mesh) {
  if (mesh.triangles.empty()) return Status::Error("embree scene: mesh has no triangles");
  if (mesh.material_ids.size() != mesh.triangles.size()) {
    return Status::Error("embree scene: material_ids has " + std::to_string(mesh.material_ids.size()) +
                         " entries for " + std::to_string(mesh.triangles.size()) + " triangles");
  }
  for (std::size_t v = 0; v < mesh.vertices_m.size(); ++v) {
    if (!mesh.vertices_m[v].allFinite()) {
      return Status::Error("embree scene: vertex " + std::to_string(v) + " is not finite");
    }
  }
  const int num_vertices = static_cast<int>(mesh.vertices_m.size());
  const int num_materials = static_cast<int>(mesh.materials.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    if (tri.minCoeff() < 0 || tri.maxCoeff() >= num_vertices) {
      return Status::Error("embree scene: triangle " + std::to_string(t) + " indexes a missing vertex");
    }
    if (mesh.material_ids[t] < 0 || mesh.material_ids[t] >= num_materials) {
      return Status::Error("embree scene: triangle " + std::to_string(t) + " has material id " +
                           std::to_string(mesh.material_ids[t]) + " of " + std::to_string(num_materials));
    }
    const Eigen::Vector3d& a = mesh.vertices_m[tri[0]];
    if ((mesh.vertices_m[tri[1]] - a).cross(mesh.vertices_m[tri[2]] - a).norm() < 1e-12) {
      return Status::Error("embree scene: triangle " + std::to_string(t) + " is degenerate");
    }
  }
  return Status::Ok();
}

Status DeviceStatus(RTCDevice device, const char* what) {
  const RTCError err = rtcGetDeviceError(device);
  if (err == RTC_ERROR_NONE) return Status::Ok();
  return Status::Error(std::string("embree scene: ") + what + " failed with error " +
                       std::to_string(static_cast<int>(err)));
}

void FillRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir_unit, double t_max, RTCRayHit* rh) {
  RTCRay& r = rh->ray;
  r.org_x = static_cast<float>(origin.x());
  r.org_y = static_cast<float>(origin.y());
  r.org_z = static_cast<float>(origin.z());
  r.dir_x = static_cast<float>(dir_unit.x());
  r.dir_y = static_cast<float>(dir_unit.y());
  r.dir_z = static_cast<float>(dir_unit.z());
  r.tnear = 0.0f;
  r.tfar = static_cast<float>(t_max);
  r.time = 0.0f;
  r.mask = std::numeric_limits<unsigned>::max();
  r.id = 0;
  r.flags = 0;
  rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh->hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

/// False for rays that cannot hit anything (zero direction, t_max <= 0, non-finite input).
bool UsableRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_max) {
  return origin.allFinite() && dir.allFinite() && dir.squaredNorm() > 0.0 && t_max > 0.0;
}

}  // namespace

Status EmbreeScene::Create(const TriangleMesh& mesh, std::unique_ptr<EmbreeScene>* out) {
  ROTOLIDAR_CHECK(out != nullptr, "EmbreeScene::Create needs an output");
  if (Status s = CheckMesh(mesh); !s) return s;
  std::unique_ptr<EmbreeScene> es(new EmbreeScene());
  es->device_ = rtcNewDevice(nullptr);
  if (!es->device_) return DeviceStatus(nullptr, "rtcNewDevice");
  rtcSetDeviceErrorFunction(es->device_, EmbreeErrorToLog, nullptr);
  es->scene_ = rtcNewScene(es->device_);
  rtcSetSceneFlags(es->scene_, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(es->scene_, RTC_BUILD_QUALITY_HIGH);

  RTCGeometry geom = rtcNewGeometry(es->device_, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), mesh.vertices_m.size()));
  auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                 3 * sizeof(unsigned), mesh.triangles.size()));
  if (!vertices || !indices) {
    rtcReleaseGeometry(geom);
    return DeviceStatus(es->device_, "buffer allocation");
  }
  for (std::size_t v = 0; v < mesh.vertices_m.size(); ++v) {
    for (int k = 0; k < 3; ++k) vertices[3 * v + k] = static_cast<float>(mesh.vertices_m[v][k]);
  }
  es->front_normals_.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) indices[3 * t + k] = static_cast<unsigned>(tri[k]);
    const Eigen::Vector3d& a = mesh.vertices_m[tri[0]];
    es->front_normals_.push_back(
        (mesh.vertices_m[tri[1]] - a).cross(mesh.vertices_m[tri[2]] - a).normalized());
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometry(es->scene_, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(es->scene_);
  if (Status s = DeviceStatus(es->device_, "scene commit"); !s) return s;
  es->material_ids_ = mesh.material_ids;
  es->materials_ = mesh.materials;
  *out = std::move(es);
  return Status::Ok();
}

EmbreeScene::~EmbreeScene() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

void EmbreeScene::FillHit(const RTCRayHit& rh, const Eigen::Vector3d& dir_unit, RayHit* out) const {
  *out = RayHit();
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return;
  const int tri = static_cast<int>(rh.hit.primID);
  const Eigen::Vector3d& n = front_normals_[static_cast<std::size_t>(tri)];
  out->hit = true;
  out->distance_m = rh.ray.tfar;
  out->front_face = n.dot(dir_unit) < 0.0;
  out->normal_world = out->front_face ? n : Eigen::Vector3d(-n);
  out->material_id = material_ids_[static_cast<std::size_t>(tri)];
  out->triangle_id = tri;
}

RayHit EmbreeScene::Intersect(const Eigen::Vector3d& origin_world, const Eigen::Vector3d& dir_world,
                              double t_max_m) const {
  RayHit result;
  if (!UsableRay(origin_world, dir_world, t_max_m)) return result;
  const Eigen::Vector3d dir_unit = dir_world.normalized();
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  FillRay(origin_world, dir_unit, t_max_m, &rh);
  rtcIntersect1(scene_, &context, &rh);
  FillHit(rh, dir_unit, &result);
  return result;
}

void EmbreeScene::IntersectBatch(const RayQuery* rays, std::size_t count, RayHit* hits) const {
  constexpr std::size_t kChunk = 256;  // bounded stack-free scratch, keeps the stream coherent
  std::vector<RTCRayHit> scratch(std::min(count, kChunk));
  std::vector<Eigen::Vector3d> dirs(scratch.size());
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  for (std::size_t begin = 0; begin < count; begin += kChunk) {
    const std::size_t n = std::min(kChunk, count - begin);
    for (std::size_t i = 0; i < n; ++i) {
      const RayQuery& q = rays[begin + i];
      if (UsableRay(q.origin_world, q.dir_world, q.t_max_m)) {
        dirs[i] = q.dir_world.normalized();
        FillRay(q.origin_world, dirs[i], q.t_max_m, &scratch[i]);
      } else {  // an empty interval: Embree reports no hit
        dirs[i] = Eigen::Vector3d::UnitX();
        FillRay(Eigen::Vector3d::Zero(), dirs[i], 0.0, &scratch[i]);
        scratch[i].ray.tnear = 1.0f;
      }
    }
    rtcIntersect1M(scene_, &context, scratch.data(), static_cast<unsigned>(n), sizeof(RTCRayHit));
    for (std::size_t i = 0; i < n; ++i) FillHit(scratch[i], dirs[i], &hits[begin + i]);
  }
}

}  // namespace rotolidar::sim
