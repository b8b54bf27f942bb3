#pragma once
// Internal to the scene loader (scene.cpp): the field lists of the scene's structs (the project's one YAML idiom,
// core/io/yaml_fields.hpp) and the readers of the values they use: vectors of n finite numbers, colours in
// [0, 1], degrees, list items, repeats and default paths. Errors are yaml::ParseError "<file>:<line>: ..." naming
// the dotted field (e.g. "materials[2].color"). Include only from scene.cpp.
#include <string>
#include <vector>

#include "core/io/yaml_fields.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim {
namespace scene_io {

using yaml::Section;

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

[[noreturn]] inline void Fail(const Section& at, const YAML::Node& node, const std::string& what) {
  yaml::Fail(at.file, node, what);
}

/// The section of item i of the list at `at`, e.g. "materials[2]".
inline Section Item(const Section& at, size_t i) {
  return Section(at.file, at.path + "[" + std::to_string(i) + "]");
}

/// A list of exactly n (<= 3) finite numbers; missing trailing entries are 0.
inline Eigen::Vector3d ReadVec(const Section& at, const YAML::Node& node, int n) {
  if (!node.IsSequence() || static_cast<int>(node.size()) != n)
    Fail(at, node, "field '" + at.path + "' must be a list of " + std::to_string(n) + " numbers");
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) yaml::ReadAs(at.file, node[i], at.path, &v[i]);
  if (!v.allFinite()) Fail(at, node, "field '" + at.path + "' must be finite");
  return v;
}

inline void ReadPoint(const Section& at, const YAML::Node& node, Eigen::Vector3d* v) { *v = ReadVec(at, node, 3); }

/// An RGB colour [r, g, b] with entries in [0, 1].
inline void ReadColor(const Section& at, const YAML::Node& node, Eigen::Vector3d* c) {
  *c = ReadVec(at, node, 3);
  if (!(c->minCoeff() >= 0.0 && c->maxCoeff() <= 1.0))
    Fail(at, node, "field '" + at.path + "' must have entries in [0, 1]");
}

/// Degrees in the file, radians in the struct.
inline void ReadDegrees(const Section& at, const YAML::Node& node, double* rad) {
  double deg = 0.0;
  yaml::ReadAs(at.file, node, at.path, &deg);
  *rad = deg * kDegToRad;
}

inline auto Point(Eigen::Vector3d* v) { return yaml::Custom(v, ReadPoint); }
inline auto Color(Eigen::Vector3d* c) { return yaml::Custom(c, ReadColor); }
inline auto Degrees(double* rad) { return yaml::Custom(rad, ReadDegrees); }

/// Parses each item of the list `node` with parse(item section, item node).
template <class Fn>
void ForEachItem(const Section& at, const YAML::Node& node, Fn parse) {
  if (!node.IsSequence()) Fail(at, node, "field '" + at.path + "' must be a list");
  for (size_t i = 0; i < node.size(); ++i) parse(Item(at, i), node[i]);
}

}  // namespace scene_io

// ---- the field lists (in the structs' namespace, so the generic visitors find them) ----

/// `color` defaults by `texture` (the loader sets it when absent).
template <class V>
void Visit(V& v, Material& m) {
  v("name", yaml::Required(&m.name)), v("albedo", yaml::Required(&m.albedo));
  v("retroreflective", &m.retroreflective), v("specular", &m.specular), v("texture", &m.texture);
  v("color", scene_io::Color(&m.color_rgb)), v("transmittance", &m.transmittance);
}

template <class V>
void Visit(V& v, TextureSpec& t) {
  v("name", yaml::Required(&t.name)), v("pattern", yaml::Required(&t.pattern));
  v("color_a", scene_io::Color(&t.color_a)), v("color_b", scene_io::Color(&t.color_b));
  v("size", &t.size_m), v("cells", &t.cells), v("grain", &t.grain), v("resolution", &t.resolution_px);
}

template <class V>
void Visit(V& v, AnnotatedElement& e) {
  v("name", yaml::Required(&e.name)), v("type", yaml::Required(&e.type));
  v("center", yaml::Required(scene_io::Point(&e.center_m))), v("width", yaml::Required(&e.width_m));
  v("height", yaml::Required(&e.height_m)), v("depth", &e.depth_m), v("yaw_deg", scene_io::Degrees(&e.yaw_rad));
  v("open", &e.open), v("primitive", &e.primitive);
}

/// The plain fields; its material or parts, path and z are read by the scene parser.
template <class V>
void Visit(V& v, DynamicObject& o) {
  v("name", yaml::Required(&o.name)), v("kind", yaml::Required(&o.kind));
  v("speed", yaml::Required(&o.speed_mps)), v("start_offset", &o.start_offset_m), v("loop", &o.loop);
}

template <class V>
void Visit(V& v, SceneLight& l) {
  v("position", scene_io::Point(&l.position_m)), v("direction", scene_io::Point(&l.direction));
  v("directional", &l.directional), v("intensity", &l.intensity), v("cast_shadow", &l.cast_shadow);
}

template <class V>
void Visit(V& v, SceneView& s) {
  v("eye", yaml::Required(scene_io::Point(&s.eye_m))), v("target", yaml::Required(scene_io::Point(&s.target_m)));
  v("fov_deg", &s.fov_deg);
}

namespace scene_io {

/// lighting.lights: each light's fields, its direction made unit, its intensity in [0, 1].
inline void ReadLights(const Section& at, const YAML::Node& node, std::vector<SceneLight>* lights) {
  ForEachItem(at, node, [&](const Section& item, const YAML::Node& n) {
    SceneLight light;
    yaml::Parse(item, n, &light);
    light.direction.normalize();
    if (!(light.intensity >= 0.0 && light.intensity <= 1.0) || !light.direction.allFinite())
      Fail(item, n, item.path + ": intensity must be in [0, 1] and direction non-zero");
    lights->push_back(light);
  });
}

}  // namespace scene_io

template <class V>
void Visit(V& v, SceneLighting& l) {
  v("ambient", &l.ambient), v("headlight", &l.headlight), v("sky", scene_io::Color(&l.sky_rgb));
  v("lights", yaml::Custom(&l.lights, scene_io::ReadLights));
}

namespace scene_io {

/// One copy of a repeated item: its name suffix and its offset [m, world axes].
struct Copy {
  std::string suffix;
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();
};

/// `repeat: {count: [n1, n2, n3], step: [dx, dy, dz]}` (1 to 3 dimensions) of an item; one copy without it.
inline std::vector<Copy> ParseRepeat(const Section& item, const YAML::Node& node) {
  const YAML::Node r = node["repeat"];
  if (!r) return {Copy{}};
  const Section at = item.Child("repeat");
  yaml::CheckKeys(at.file, r, {"count", "step"}, at.path);
  const YAML::Node count = r["count"], step = r["step"];
  if (!count || !count.IsSequence() || count.size() < 1 || count.size() > 3)
    Fail(at, r, "field '" + at.Field("count") + "' must be a list of 1 to 3 integers");
  const int dims = static_cast<int>(count.size());
  if (!step) Fail(at, r, "missing required key 'step' in " + at.path);
  const Eigen::Vector3d step_m = ReadVec(at.Child("step"), step, dims);
  int n[3] = {1, 1, 1};
  for (int d = 0; d < dims; ++d) {
    yaml::ReadAs(at.file, count[d], at.Field("count"), &n[d]);
    if (n[d] < 1 || n[d] > 1000) Fail(at, count[d], "field '" + at.Field("count") + "' must be in [1, 1000]");
  }
  std::vector<Copy> copies;
  for (int i = 0; i < n[0]; ++i) {
    for (int j = 0; j < n[1]; ++j) {
      for (int k = 0; k < n[2]; ++k) {
        Copy c;
        const int index[3] = {i, j, k};
        for (int d = 0; d < dims; ++d) c.suffix += "_" + std::to_string(index[d]);
        c.offset_m = Eigen::Vector3d(i * step_m.x(), j * step_m.y(), k * step_m.z());
        copies.push_back(c);
      }
    }
  }
  return copies;
}

/// `paths: {handheld|wheeled|car: [[x, y], [x, y, dwell_s], ...]}` in the file's order. A carrier the scene
/// already has a path for (from the base scene) gets the new path in its old place in path_order.
inline void ParsePaths(const Section& at, const YAML::Node& node, Scene* scene) {
  yaml::CheckKeys(at.file, node, {"handheld", "wheeled", "car"}, at.path);
  for (const auto& kv : node) {
    const std::string carrier = kv.first.as<std::string>();
    if (!scene->default_paths.count(carrier)) scene->path_order.push_back(carrier);
    std::vector<Waypoint2d>& path = scene->default_paths[carrier];
    path.clear();
    ForEachItem(at.Child(carrier), kv.second, [&](const Section& item, const YAML::Node& w) {
      const Eigen::Vector3d v = ReadVec(item, w, w.IsSequence() && w.size() == 3 ? 3 : 2);
      path.push_back(Waypoint2d{v.x(), v.y(), v.z()});
    });
  }
}

}  // namespace scene_io
}  // namespace rotolidar::sim
