// Scene file loader (docs/scene_format.md). Every error names file:line and the key; nothing throws out.
#include <cmath>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "sim/world/scene.hpp"

namespace rotolidar::sim {
namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

/// Thrown inside the loader only, caught in LoadScene: carries a finished "file:line: message".
struct ParseError {
  std::string message;
};

class SceneParser {
 public:
  explicit SceneParser(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void Fail(const YAML::Node& at, const std::string& what) const {
    std::ostringstream os;
    os << path_ << ":" << (at.Mark().line + 1) << ": " << what;
    throw ParseError{os.str()};
  }

  /// Every key of `map` must be in `allowed`.
  void CheckKeys(const YAML::Node& map, const std::set<std::string>& allowed, const std::string& context) const {
    if (!map.IsMap()) Fail(map, context + ": expected a mapping");
    for (const auto& kv : map) {
      const std::string key = kv.first.as<std::string>();
      if (!allowed.count(key)) Fail(kv.first, "unknown key '" + key + "' in " + context);
    }
  }

  template <typename T>
  T Get(const YAML::Node& map, const std::string& key, const std::string& context) const {
    const YAML::Node node = map[key];
    if (!node) Fail(map, "missing key '" + key + "' in " + context);
    return As<T>(node, key, context);
  }

  template <typename T>
  T GetOr(const YAML::Node& map, const std::string& key, const T& fallback, const std::string& context) const {
    const YAML::Node node = map[key];
    return node ? As<T>(node, key, context) : fallback;
  }

  Eigen::Vector3d Vec(const YAML::Node& map, const std::string& key, int n, const std::string& context) const {
    const YAML::Node node = map[key];
    if (!node) Fail(map, "missing key '" + key + "' in " + context);
    if (!node.IsSequence() || static_cast<int>(node.size()) != n) {
      Fail(node, "'" + key + "' in " + context + " must be a list of " + std::to_string(n) + " numbers");
    }
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    for (int i = 0; i < n; ++i) v[i] = As<double>(node[i], key, context);
    return v;
  }

  Scene Parse(const YAML::Node& root) const;

 private:
  template <typename T>
  T As(const YAML::Node& node, const std::string& key, const std::string& context) const {
    try {
      return node.as<T>();
    } catch (const YAML::Exception&) {
      Fail(node, "bad value for '" + key + "' in " + context);
    }
  }

  Material ParseMaterial(const YAML::Node& node) const;
  Primitive ParsePrimitive(const YAML::Node& node, const Scene& scene) const;
  AnnotatedElement ParseElement(const YAML::Node& node) const;
  Eigen::Vector3d ParseOrientation(const YAML::Node& node, const std::string& context) const;
  int MaterialRef(const YAML::Node& node, const std::string& key, const Scene& scene,
                  const std::string& context) const;

  std::string path_;
};

Material SceneParser::ParseMaterial(const YAML::Node& node) const {
  CheckKeys(node, {"name", "albedo", "retroreflective", "texture"}, "material");
  Material m;
  m.name = Get<std::string>(node, "name", "material");
  const std::string context = "material '" + m.name + "'";
  m.albedo = Get<double>(node, "albedo", context);
  if (!(m.albedo >= 0.0 && m.albedo <= 1.0)) Fail(node["albedo"], "albedo must be in [0, 1] in " + context);
  m.retroreflective = GetOr<bool>(node, "retroreflective", false, context);
  m.texture = GetOr<std::string>(node, "texture", "", context);
  return m;
}

Eigen::Vector3d SceneParser::ParseOrientation(const YAML::Node& node, const std::string& context) const {
  if (node["yaw_deg"] && node["rpy_deg"]) Fail(node, "give either yaw_deg or rpy_deg in " + context);
  if (node["rpy_deg"]) return Vec(node, "rpy_deg", 3, context) * kDegToRad;
  return Eigen::Vector3d(0.0, 0.0, GetOr<double>(node, "yaw_deg", 0.0, context) * kDegToRad);
}

int SceneParser::MaterialRef(const YAML::Node& node, const std::string& key, const Scene& scene,
                             const std::string& context) const {
  const std::string name = Get<std::string>(node, key, context);
  const int id = scene.FindMaterial(name);
  if (id < 0) Fail(node[key], "unknown material '" + name + "' in " + context);
  return id;
}

Primitive SceneParser::ParsePrimitive(const YAML::Node& node, const Scene& scene) const {
  if (!node.IsMap()) Fail(node, "primitive: expected a mapping");
  Primitive p;
  const std::string type = Get<std::string>(node, "type", "primitive");
  p.name = GetOr<std::string>(node, "name", type, "primitive");
  const std::string context = "primitive '" + p.name + "'";
  const std::set<std::string> common{"type", "name", "center", "yaw_deg", "rpy_deg", "material"};
  std::set<std::string> allowed = common;
  if (type == "box") {
    p.type = PrimitiveType::kBox;
    allowed.insert({"size", "inward", "floor_material", "ceiling_material"});
  } else if (type == "quad" || type == "plane") {
    p.type = PrimitiveType::kQuad;
    allowed.insert("size");
  } else if (type == "cylinder") {
    p.type = PrimitiveType::kCylinder;
    allowed.insert({"radius", "height", "segments"});
  } else {
    Fail(node["type"], "unknown primitive type '" + type + "' (box, quad, plane, cylinder) in " + context);
  }
  CheckKeys(node, allowed, context);
  p.center_m = Vec(node, "center", 3, context);
  p.rpy_rad = ParseOrientation(node, context);
  p.material_id = MaterialRef(node, "material", scene, context);
  if (p.type == PrimitiveType::kBox) {
    p.size_m = Vec(node, "size", 3, context);
    p.inward = GetOr<bool>(node, "inward", false, context);
    if (node["floor_material"]) p.floor_material_id = MaterialRef(node, "floor_material", scene, context);
    if (node["ceiling_material"]) p.ceiling_material_id = MaterialRef(node, "ceiling_material", scene, context);
  } else if (p.type == PrimitiveType::kQuad) {
    p.size_m = Vec(node, "size", 2, context);
  } else {
    p.radius_m = Get<double>(node, "radius", context);
    p.height_m = Get<double>(node, "height", context);
    p.segments = GetOr<int>(node, "segments", 24, context);
  }
  std::string error;
  Scene one;  // validate this primitive alone so the error carries its line
  one.materials = scene.materials;
  one.primitives = {p};
  one.bounds = Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  if (!one.Validate(&error)) Fail(node, error);
  return p;
}

AnnotatedElement SceneParser::ParseElement(const YAML::Node& node) const {
  CheckKeys(node, {"name", "type", "center", "width", "height", "yaw_deg"}, "element");
  AnnotatedElement e;
  e.name = Get<std::string>(node, "name", "element");
  const std::string context = "element '" + e.name + "'";
  e.type = Get<std::string>(node, "type", context);
  if (e.type != "door" && e.type != "window" && e.type != "column") {
    Fail(node["type"], "type must be door, window or column in " + context);
  }
  e.center_m = Vec(node, "center", 3, context);
  e.width_m = Get<double>(node, "width", context);
  e.height_m = Get<double>(node, "height", context);
  if (!(e.width_m > 0.0 && e.height_m > 0.0)) Fail(node, "width and height must be > 0 in " + context);
  e.yaw_rad = GetOr<double>(node, "yaw_deg", 0.0, context) * kDegToRad;
  return e;
}

Scene SceneParser::Parse(const YAML::Node& root) const {
  CheckKeys(root, {"format_version", "name", "closed", "bounds", "materials", "primitives", "elements"}, "scene");
  const int version = Get<int>(root, "format_version", "scene");
  if (version != 1) Fail(root["format_version"], "unsupported format_version " + std::to_string(version));
  Scene scene;
  scene.source_path = path_;
  scene.name = GetOr<std::string>(root, "name", "", "scene");
  scene.closed = GetOr<bool>(root, "closed", false, "scene");
  const YAML::Node bounds = root["bounds"];
  if (!bounds) Fail(root, "missing key 'bounds' in scene");
  CheckKeys(bounds, {"min", "max"}, "bounds");
  scene.bounds = Eigen::AlignedBox3d(Vec(bounds, "min", 3, "bounds"), Vec(bounds, "max", 3, "bounds"));
  if (scene.bounds.isEmpty()) Fail(bounds, "bounds: min must be < max");
  const YAML::Node materials = root["materials"], primitives = root["primitives"], elements = root["elements"];
  if (!materials || !materials.IsSequence()) Fail(root, "'materials' must be a list");
  for (const auto& m : materials) {
    scene.materials.push_back(ParseMaterial(m));
    if (scene.FindMaterial(scene.materials.back().name) + 1 != static_cast<int>(scene.materials.size())) {
      Fail(m, "material '" + scene.materials.back().name + "' defined twice");
    }
  }
  if (!primitives || !primitives.IsSequence()) Fail(root, "'primitives' must be a list");
  for (const auto& p : primitives) scene.primitives.push_back(ParsePrimitive(p, scene));
  if (elements) {
    if (!elements.IsSequence()) Fail(elements, "'elements' must be a list");
    for (const auto& e : elements) scene.elements.push_back(ParseElement(e));
  }
  std::string error;
  if (!scene.Validate(&error)) Fail(root, error);
  return scene;
}

}  // namespace

Status LoadScene(const std::string& path, Scene* scene) {
  ROTOLIDAR_CHECK(scene != nullptr, "LoadScene needs an output");
  try {
    const YAML::Node root = YAML::LoadFile(path);
    *scene = SceneParser(path).Parse(root);
    return Status::Ok();
  } catch (const ParseError& e) {
    return Status::Error(e.message);
  } catch (const YAML::BadFile&) {
    return Status::Error(path + ": cannot open scene file");
  } catch (const YAML::ParserException& e) {
    return Status::Error(path + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg);
  } catch (const YAML::Exception& e) {
    return Status::Error(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

}  // namespace rotolidar::sim
