// Dynamic objects: pose along their paths and default bodies.
#include "sim/world/scene_dynamic.hpp"
#include "core/util/log.hpp"

#include <cmath>

namespace rotolidar::sim {
namespace {

constexpr double kHalfPi = 1.57079632679489661923;

/// The path's corners in order, closed (first point repeated at the end) when the object loops.
std::vector<Eigen::Vector3d> Corners(const DynamicObject& object) {
  std::vector<Eigen::Vector3d> c = object.path_m;
  if (object.loop && !c.empty()) c.push_back(c.front());
  return c;
}

double HorizontalLength(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return (b - a).head<2>().norm(); }

Primitive Part(PrimitiveType type, const std::string& name, const Eigen::Vector3d& center_m, int material_id) {
  Primitive p;
  p.type = type;
  p.name = name;
  p.center_m = center_m;
  p.material_id = material_id;
  return p;
}

Primitive BoxPart(const std::string& name, const Eigen::Vector3d& center_m, const Eigen::Vector3d& size_m,
                  int material_id) {
  Primitive p = Part(PrimitiveType::kBox, name, center_m, material_id);
  p.size_m = size_m;
  return p;
}

Primitive CylinderPart(const std::string& name, const Eigen::Vector3d& center_m, double radius_m, double height_m,
                       int segments, double roll_rad, int material_id) {
  Primitive p = Part(PrimitiveType::kCylinder, name, center_m, material_id);
  p.radius_m = radius_m;
  p.height_m = height_m;
  p.segments = segments;
  p.rpy_rad = Eigen::Vector3d(roll_rad, 0.0, 0.0);
  return p;
}

}  // namespace

double PathLength(const DynamicObject& object) {
  const std::vector<Eigen::Vector3d> c = Corners(object);
  double length = 0.0;
  for (std::size_t i = 1; i < c.size(); ++i) length += HorizontalLength(c[i - 1], c[i]);
  return length;
}

Eigen::Isometry3d DynamicObjectPose(const DynamicObject& object, Seconds t) {
  const std::vector<Eigen::Vector3d> c = Corners(object);
  const double length = PathLength(object);
  ROTOLIDAR_CHECK(c.size() >= 2 && length > 0.0, "dynamic object '" << object.name << "' has no path");
  const double period = object.loop ? length : 2.0 * length;
  double s = std::fmod(object.start_offset_m + object.speed_mps * t, period);
  if (s < 0.0) s += period;
  bool backwards = false;
  if (s > length) {  // the return leg of a back-and-forth path
    s = period - s;
    backwards = true;
  }
  std::size_t i = 1;
  double segment = HorizontalLength(c[0], c[1]);
  while (i + 1 < c.size() && s > segment) {
    s -= segment;
    ++i;
    segment = HorizontalLength(c[i - 1], c[i]);
  }
  const double f = segment > 0.0 ? std::min(s / segment, 1.0) : 0.0;
  const Eigen::Vector3d p = c[i - 1] + f * (c[i] - c[i - 1]);
  const Eigen::Vector2d dir = (c[i] - c[i - 1]).head<2>();
  const double heading = (segment > 0.0 ? std::atan2(dir.y(), dir.x()) : 0.0) + (backwards ? 2.0 * kHalfPi : 0.0);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = p;
  return T;
}

std::vector<Primitive> DefaultBody(const std::string& kind, int material_id) {
  using V = Eigen::Vector3d;
  if (kind == "person") {
    return {BoxPart("legs", V(0, 0, 0.425), V(0.25, 0.36, 0.85), material_id),
            BoxPart("torso", V(0, 0, 1.145), V(0.28, 0.46, 0.61), material_id),
            CylinderPart("head", V(0, 0, 1.60), 0.11, 0.26, 12, 0.0, material_id)};
  }
  if (kind == "car") {
    std::vector<Primitive> parts = {BoxPart("body", V(0, 0, 0.65), V(4.4, 1.8, 0.7), material_id),
                                    BoxPart("cabin", V(-0.3, 0, 1.24), V(2.3, 1.6, 0.5), material_id)};
    for (double x : {-1.35, 1.35}) {
      for (double y : {-0.8, 0.8}) {  // wheel axes along body y
        parts.push_back(CylinderPart("wheel", V(x, y, 0.32), 0.32, 0.24, 16, kHalfPi, material_id));
      }
    }
    return parts;
  }
  return {};
}

TriangleMesh BuildObjectMesh(const Scene& scene, const DynamicObject& object) {
  TriangleMesh mesh;
  mesh.materials = scene.materials;
  AppendPrimitives(object.parts, scene.meshes, &mesh);
  return mesh;
}

bool ValidateDynamicObject(const DynamicObject& object, const Scene& scene, std::string* error) {
  const auto fail = [&](const std::string& what) {
    if (error) *error = "dynamic object '" + object.name + "': " + what;
    return false;
  };
  if (object.kind != "person" && object.kind != "car") return fail("kind must be person or car");
  if (object.parts.empty()) return fail("has no parts");
  std::string why;
  for (const Primitive& part : object.parts) {
    if (!ValidatePrimitive(part, scene, &why)) return fail(why);
  }
  if (object.path_m.size() < 2) return fail("path needs >= 2 waypoints");
  for (const Eigen::Vector3d& p : object.path_m) {
    if (!p.allFinite()) return fail("path has a non-finite waypoint");
  }
  if (!(PathLength(object) > 1e-6)) return fail("path has zero horizontal length");
  if (!(object.speed_mps > 0.0 && std::isfinite(object.speed_mps))) return fail("speed must be > 0");
  if (!std::isfinite(object.start_offset_m)) return fail("non-finite start offset");
  return true;
}

}  // namespace rotolidar::sim
