#include "sim/scene_carrier.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rotolidar::sim {
namespace {

std::string Fmt(const char* format, double a, double b) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), format, a, b);
  return buf;
}

std::string TimeText(double t) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.2f s", t);
  return buf;
}

std::string Point3(const Eigen::Vector3d& p) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "(%.2f, %.2f, %.2f) m", p.x(), p.y(), p.z());
  return buf;
}

std::string JoinOrNone(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out.empty() ? "none (the scene file has no `paths:`)" : out;
}

/// The waypoint polygon a carrier follows (empty for the scripted loop and KITTI), and whether it closes.
std::vector<Waypoint2d> CarrierWaypoints(const CarrierConfig& c, bool* closed) {
  *closed = false;
  switch (c.type) {
    case CarrierType::kHandheld: *closed = c.handheld.closed_loop; return c.handheld.waypoints;
    case CarrierType::kWheeled: *closed = c.wheeled.closed_loop; return c.wheeled.waypoints;
    case CarrierType::kCar: {
      if (c.car.waypoints_file.empty()) return c.car.waypoints;
      std::vector<CarWaypoint> points;
      std::vector<Waypoint2d> out;
      if (LoadCarWaypointsCsv(c.car.waypoints_file, &points))
        for (const CarWaypoint& p : points) out.push_back({p.x_m, p.y_m, 0.0});
      return out;
    }
    default: return {};
  }
}

double DistanceToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double s = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + s * ab - p).norm();
}

/// "on the leg from waypoint i (x, y) to waypoint j (x, y)" for the leg nearest to p, or a description of a
/// carrier without waypoints.
std::string WhereOnPath(const CarrierConfig& c, const Eigen::Vector3d& p) {
  bool closed = false;
  const std::vector<Waypoint2d> w = CarrierWaypoints(c, &closed);
  if (c.type == CarrierType::kScriptedLoop) {
    const ScriptedBaseMotionConfig& s = c.scripted_loop;
    return "on the scripted loop around " + Fmt("(%.2f, %.2f)", s.center_x_m, s.center_y_m) + " with radii " +
           Fmt("%.2f x %.2f m", s.radius_x_m, s.radius_y_m);
  }
  if (w.size() < 2) return "on the " + std::string(CarrierTypeName(c.type)) + " path";
  const size_t legs = closed ? w.size() : w.size() - 1;
  size_t best = 0;
  double best_d = 1e300;
  for (size_t i = 0; i < legs; ++i) {
    const Waypoint2d& a = w[i];
    const Waypoint2d& b = w[(i + 1) % w.size()];
    const double d = DistanceToSegment(p.head<2>(), {a.x_m, a.y_m}, {b.x_m, b.y_m});
    if (d < best_d) best_d = d, best = i;
  }
  const size_t next = (best + 1) % w.size();
  return "on the leg from waypoint " + std::to_string(best) + " " + Fmt("(%.2f, %.2f)", w[best].x_m, w[best].y_m) +
         " to waypoint " + std::to_string(next) + " " + Fmt("(%.2f, %.2f)", w[next].x_m, w[next].y_m);
}

/// Empty when p lies in the bounds, else which bound it passes ("x 16.30 > bounds max 16.00").
std::string OutsideBounds(const Eigen::AlignedBox3d& bounds, const Eigen::Vector3d& p) {
  const char* axes[] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    if (p[a] < bounds.min()[a]) return std::string(axes[a]) + Fmt(" %.2f < bounds min %.2f", p[a], bounds.min()[a]);
    if (p[a] > bounds.max()[a]) return std::string(axes[a]) + Fmt(" %.2f > bounds max %.2f", p[a], bounds.max()[a]);
  }
  return "";
}

/// The first static hit on the segment from a to b (dynamic objects are stepped over), or no hit.
RayHit StaticHitOnSegment(const EmbreeScene& embree, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double length = (b - a).norm();
  if (!(length > 1e-9)) return RayHit{};
  const Eigen::Vector3d dir = (b - a) / length;
  double travelled = 0.0;
  for (int k = 0; k < 64; ++k) {
    RayHit hit = embree.Intersect(a + travelled * dir, dir, length - travelled);
    if (!hit.hit || hit.object_id < 0) {
      hit.distance_m += travelled;
      return hit;
    }
    travelled += hit.distance_m + 1e-4;
    if (travelled >= length) break;
  }
  return RayHit{};
}

std::string PrimitiveName(const Scene& scene, int triangle_id) {
  const TriangleMesh mesh = BuildMesh(scene);  // only on the error path: names the primitive
  if (triangle_id < 0 || size_t(triangle_id) >= mesh.primitive_ids.size()) return "static geometry";
  const int id = mesh.primitive_ids[size_t(triangle_id)];
  if (id < 0 || size_t(id) >= scene.primitives.size()) return "static geometry";
  return "primitive '" + scene.primitives[size_t(id)].name + "'";
}

}  // namespace

std::vector<std::string> SceneCarriers(const Scene& scene) {
  std::vector<std::string> out = scene.path_order;
  for (const auto& [name, path_unused] : scene.default_paths)
    if (std::find(out.begin(), out.end(), name) == out.end()) out.push_back(name);
  return out;
}

void ChooseSceneCarrier(const Scene& scene, CarrierConfig* carrier) {
  const std::vector<std::string> offered = SceneCarriers(scene);
  CarrierType type = CarrierType::kScriptedLoop;
  const bool handheld = std::find(offered.begin(), offered.end(), "handheld") != offered.end();
  if (handheld) type = CarrierType::kHandheld;
  else if (!offered.empty()) CarrierTypeFromName(offered.front(), &type);
  carrier->type = type;
}

Status FillScenePath(const Scene& scene, CarrierConfig* carrier) {
  std::vector<Waypoint2d>* waypoints = nullptr;
  if (carrier->type == CarrierType::kHandheld) waypoints = &carrier->handheld.waypoints;
  if (carrier->type == CarrierType::kWheeled) waypoints = &carrier->wheeled.waypoints;
  if (carrier->type == CarrierType::kCar && carrier->car.waypoints_file.empty()) waypoints = &carrier->car.waypoints;
  if (!waypoints || !waypoints->empty()) return Status::Ok();
  const std::string name = CarrierTypeName(carrier->type);
  const auto it = scene.default_paths.find(name);
  if (it == scene.default_paths.end())
    return Status::Error("scene '" + scene.name + "' has no " + name + " path; it offers: " +
                         JoinOrNone(SceneCarriers(scene)) + " (or give carrier." + name + ".waypoints in --config)");
  *waypoints = it->second;
  return Status::Ok();
}

namespace {

/// True when the samples within `window` of k, all moved by `shift`, are clear of static geometry.
bool ClearWhenMoved(const std::vector<Eigen::Vector3d>& samples, size_t k, const Eigen::Vector3d& shift,
                    size_t window, const EmbreeScene& embree) {
  const size_t first = k > window ? k - window : 1;
  const size_t last = std::min(samples.size() - 1, k + window);
  for (size_t j = first; j <= last; ++j)
    if (StaticHitOnSegment(embree, samples[j - 1] + shift, samples[j] + shift).hit) return false;
  return true;
}

/// True when the path near sample k (the segment k-1 -> k hit a surface with normal n) only dips less than
/// `graze_m` into the obstacle: moved graze_m along n or against it (entering or leaving), it is clear.
bool OnlyGrazes(const std::vector<Eigen::Vector3d>& samples, size_t k, const Eigen::Vector3d& n, double graze_m,
                size_t window, const EmbreeScene& embree) {
  if (!(graze_m > 0) || !(n.norm() > 0)) return false;
  const Eigen::Vector3d shift = graze_m * n.normalized();
  return ClearWhenMoved(samples, k, shift, window, embree) || ClearWhenMoved(samples, k, -shift, window, embree);
}

}  // namespace

Status CheckCarrierPath(const CarrierConfig& carrier, const BaseMotion& motion, double duration_s,
                        const Scene& scene, const EmbreeScene& embree, const PathCheckOptions& options) {
  const size_t n = std::max<size_t>(
      1, std::min(options.max_samples, size_t(std::ceil(duration_s / options.sample_dt_s - 1e-9))));
  const double dt = duration_s / double(n);
  const std::string what = "scene '" + scene.name + "': the " + CarrierTypeName(carrier.type) + " path ";
  std::vector<Eigen::Vector3d> samples(n + 1);
  for (size_t k = 0; k <= n; ++k) samples[k] = motion.At(double(k) * dt).T_world_base.translation();
  const size_t window = size_t(std::ceil(options.graze_window_s / dt));
  for (size_t k = 0; k <= n; ++k) {
    const Eigen::Vector3d& p = samples[k];
    if (const std::string out = OutsideBounds(scene.bounds, p); !out.empty())
      return Status::Error(what + "leaves the scene's bounds at t = " + TimeText(double(k) * dt) + ", " + Point3(p) +
                           " (" + out + "), " + WhereOnPath(carrier, p));
    if (k == 0) continue;
    const RayHit hit = StaticHitOnSegment(embree, samples[k - 1], p);
    if (!hit.hit || OnlyGrazes(samples, k, hit.normal_world, options.graze_m, window, embree)) continue;
    const Eigen::Vector3d q = samples[k - 1] + hit.distance_m * (p - samples[k - 1]).normalized();
    return Status::Error(what + "crosses " + PrimitiveName(scene, hit.triangle_id) + " at t = " +
                         TimeText(double(k) * dt) + ", " + Point3(q) + ", " + WhereOnPath(carrier, q));
  }
  return Status::Ok();
}

}  // namespace rotolidar::sim
