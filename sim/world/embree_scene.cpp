// Embree 3 scene: one triangle geometry for the static mesh (instanced when dynamic objects exist), one instance
// per dynamic object; robust traversal (no leaks along shared edges).
#include "sim/world/embree_scene.hpp"

#include <limits>

#include "sim/world/scene_dynamic.hpp"
#include "core/util/log.hpp"
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

void SetTransform(RTCGeometry instance, const Eigen::Isometry3d& T) {
  float xfm[12];  // 3x4 column major: the rotation's columns, then the translation
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 3; ++r) xfm[3 * c + r] = static_cast<float>(T.matrix()(r, c));
  }
  rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
  rtcCommitGeometry(instance);
}

RTCScene NewScene(RTCDevice device, bool top_level) {
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneFlags(scene, top_level ? RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_DYNAMIC : RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene, top_level ? RTC_BUILD_QUALITY_LOW : RTC_BUILD_QUALITY_HIGH);
  return scene;
}

/// Instances `child` into `top`, returns its geometry id.
unsigned AttachInstance(RTCDevice device, RTCScene top, RTCScene child, const Eigen::Isometry3d& T) {
  RTCGeometry instance = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
  rtcSetGeometryInstancedScene(instance, child);
  rtcSetGeometryTimeStepCount(instance, 1);
  SetTransform(instance, T);
  const unsigned id = rtcAttachGeometry(top, instance);
  rtcReleaseGeometry(instance);
  return id;
}

/// rtcPointQuery's callback: hands the triangle to the caller's visitor and shrinks the search to its answer.
bool VisitPointQueryCandidate(RTCPointQueryFunctionArguments* args) {
  const auto& visit = *static_cast<const std::function<double(int)>*>(args->userPtr);
  const float radius = static_cast<float>(visit(static_cast<int>(args->primID)));
  if (!(radius < args->query->radius)) return false;
  args->query->radius = radius;
  return true;  // the radius shrank: Embree re-culls the remaining nodes
}

/// Bounds of the static triangles of retroreflective materials, one box per primitive.
std::vector<Eigen::AlignedBox3d> RetroreflectiveBounds(const TriangleMesh& mesh) {
  std::vector<Eigen::AlignedBox3d> boxes;
  std::vector<int> box_of_primitive;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (!mesh.materials[static_cast<std::size_t>(mesh.material_ids[t])].retroreflective) continue;
    const std::size_t p = static_cast<std::size_t>(t < mesh.primitive_ids.size() ? std::max(mesh.primitive_ids[t], 0) : 0);
    if (box_of_primitive.size() <= p) box_of_primitive.resize(p + 1, -1);
    if (box_of_primitive[p] < 0) {
      box_of_primitive[p] = static_cast<int>(boxes.size());
      boxes.emplace_back();
    }
    Eigen::AlignedBox3d& box = boxes[static_cast<std::size_t>(box_of_primitive[p])];
    for (int k = 0; k < 3; ++k) box.extend(mesh.vertices_m[mesh.triangles[t][k]]);
  }
  return boxes;
}

}  // namespace

Status EmbreeScene::AddTriangles(RTCScene target, const TriangleMesh& mesh, Part* part) {
  if (Status s = CheckMesh(mesh); !s) return s;
  RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), mesh.vertices_m.size()));
  auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                 3 * sizeof(unsigned), mesh.triangles.size()));
  if (!vertices || !indices) {
    rtcReleaseGeometry(geom);
    return DeviceStatus(device_, "buffer allocation");
  }
  for (std::size_t v = 0; v < mesh.vertices_m.size(); ++v) {
    for (int k = 0; k < 3; ++k) vertices[3 * v + k] = static_cast<float>(mesh.vertices_m[v][k]);
  }
  part->front_normals.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) indices[3 * t + k] = static_cast<unsigned>(tri[k]);
    const Eigen::Vector3d& a = mesh.vertices_m[tri[0]];
    part->front_normals.push_back((mesh.vertices_m[tri[1]] - a).cross(mesh.vertices_m[tri[2]] - a).normalized());
  }
  part->material_ids = mesh.material_ids;
  rtcCommitGeometry(geom);
  rtcAttachGeometry(target, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(target);
  return DeviceStatus(device_, "scene commit");
}

Status EmbreeScene::Create(const TriangleMesh& mesh, std::unique_ptr<EmbreeScene>* out) {
  ROTOLIDAR_CHECK(out != nullptr, "EmbreeScene::Create needs an output");
  if (Status s = CheckMesh(mesh); !s) return s;
  std::unique_ptr<EmbreeScene> es(new EmbreeScene());
  es->device_ = rtcNewDevice(nullptr);
  if (!es->device_) return DeviceStatus(nullptr, "rtcNewDevice");
  rtcSetDeviceErrorFunction(es->device_, EmbreeErrorToLog, nullptr);
  es->scene_ = NewScene(es->device_, false);
  if (Status s = es->AddTriangles(es->scene_, mesh, &es->static_part_); !s) return s;
  es->materials_ = mesh.materials;
  es->retro_bounds_ = RetroreflectiveBounds(mesh);
  *out = std::move(es);
  return Status::Ok();
}

Status EmbreeScene::AddObject(const Scene& scene, const DynamicObject& object) {
  Object o;
  o.description = object;
  o.scene = NewScene(device_, false);
  objects_.push_back(o);  // owned from here on (released in the destructor)
  Object& added = objects_.back();
  if (Status s = AddTriangles(added.scene, BuildObjectMesh(scene, object), &added.part); !s) {
    return Status::Error(s.message + " (dynamic object '" + object.name + "')");
  }
  added.instance_id = AttachInstance(device_, scene_, added.scene, Eigen::Isometry3d::Identity());
  if (object_of_instance_.size() <= added.instance_id) object_of_instance_.resize(added.instance_id + 1, -1);
  object_of_instance_[added.instance_id] = static_cast<int>(objects_.size()) - 1;
  return Status::Ok();
}

Status EmbreeScene::Create(const Scene& scene, std::unique_ptr<EmbreeScene>* out, Seconds t0) {
  ROTOLIDAR_CHECK(out != nullptr, "EmbreeScene::Create needs an output");
  const TriangleMesh mesh = BuildMesh(scene);
  if (scene.dynamic_objects.empty()) return Create(mesh, out);
  if (Status s = CheckMesh(mesh); !s) return s;
  std::unique_ptr<EmbreeScene> es(new EmbreeScene());
  es->device_ = rtcNewDevice(nullptr);
  if (!es->device_) return DeviceStatus(nullptr, "rtcNewDevice");
  rtcSetDeviceErrorFunction(es->device_, EmbreeErrorToLog, nullptr);
  es->scene_ = NewScene(es->device_, true);
  es->static_scene_ = NewScene(es->device_, false);
  if (Status s = es->AddTriangles(es->static_scene_, mesh, &es->static_part_); !s) return s;
  es->static_instance_id_ = AttachInstance(es->device_, es->scene_, es->static_scene_, Eigen::Isometry3d::Identity());
  es->object_of_instance_.assign(es->static_instance_id_ + 1, -1);
  es->objects_.reserve(scene.dynamic_objects.size());
  for (const DynamicObject& object : scene.dynamic_objects) {
    if (Status s = es->AddObject(scene, object); !s) return s;
  }
  es->materials_ = mesh.materials;
  es->retro_bounds_ = RetroreflectiveBounds(mesh);
  es->SetTime(t0);
  if (Status s = DeviceStatus(es->device_, "top-level commit"); !s) return s;
  *out = std::move(es);
  return Status::Ok();
}

void EmbreeScene::SetTime(Seconds t) {
  time_s_ = t;
  if (objects_.empty()) return;
  for (Object& o : objects_) {
    o.T_world_body = DynamicObjectPose(o.description, t);
    SetTransform(rtcGetGeometry(scene_, o.instance_id), o.T_world_body);
  }
  rtcCommitScene(scene_);
}

std::size_t EmbreeScene::num_triangles() const {
  std::size_t n = static_part_.front_normals.size();
  for (const Object& o : objects_) n += o.part.front_normals.size();
  return n;
}

EmbreeScene::~EmbreeScene() {
  if (scene_) rtcReleaseScene(scene_);
  if (static_scene_) rtcReleaseScene(static_scene_);
  for (Object& o : objects_) {
    if (o.scene) rtcReleaseScene(o.scene);
  }
  if (device_) rtcReleaseDevice(device_);
}

void EmbreeScene::FillHit(const RTCRayHit& rh, const Eigen::Vector3d& dir_unit, RayHit* out) const {
  *out = RayHit();
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return;
  const unsigned instance = rh.hit.instID[0];
  const int object = instance == RTC_INVALID_GEOMETRY_ID ? -1 : object_of_instance_[instance];
  const Part& part = object < 0 ? static_part_ : objects_[static_cast<std::size_t>(object)].part;
  const std::size_t tri = rh.hit.primID;
  Eigen::Vector3d n = part.front_normals[tri];
  if (object >= 0) n = objects_[static_cast<std::size_t>(object)].T_world_body.linear() * n;
  out->hit = true;
  out->distance_m = rh.ray.tfar;
  out->front_face = n.dot(dir_unit) < 0.0;
  out->normal_world = out->front_face ? n : Eigen::Vector3d(-n);
  out->material_id = part.material_ids[tri];
  out->triangle_id = static_cast<int>(tri);
  out->object_id = object;
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

void EmbreeScene::VisitStaticTrianglesNear(const Eigen::Vector3d& p, double radius_m,
                                           const std::function<double(int)>& visit) const {
  RTCPointQuery query;
  query.x = static_cast<float>(p.x());
  query.y = static_cast<float>(p.y());
  query.z = static_cast<float>(p.z());
  query.time = 0.0f;
  query.radius = static_cast<float>(radius_m);
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  // With dynamic objects the static world is its own scene (instanced with identity); without, it is scene_.
  RTCScene static_world = static_scene_ ? static_scene_ : scene_;
  rtcPointQuery(static_world, &query, &context, VisitPointQueryCandidate,
                const_cast<std::function<double(int)>*>(&visit));
}

}  // namespace rotolidar::sim
