// Scene file loader (docs/scene_format.md). Every error names file:line and the key; nothing throws out.
#include <cmath>
#include <filesystem>
#include <set>

#include "sim/world/mesh_io.hpp"
#include "sim/world/scene.hpp"
#include "sim/world/scene_dynamic.hpp"
#include "sim/world/scene_yaml.hpp"

namespace rotolidar::sim {
namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

/// One copy of a repeated item: its name suffix and its offset [m, world axes].
struct Copy {
  std::string suffix;
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();
};

class SceneParser {
 public:
  explicit SceneParser(const std::string& path)
      : y_(path), dir_(std::filesystem::path(path).parent_path().string()) {}

  Scene Parse(const YAML::Node& root);

 private:
  Material ParseMaterial(const YAML::Node& node) const;
  TextureSpec ParseTexture(const YAML::Node& node) const;
  std::vector<Copy> ParseRepeat(const YAML::Node& node, const std::string& context) const;
  std::vector<Primitive> ParsePrimitives(const YAML::Node& list, const std::string& context, Scene* scene);
  Primitive ParsePrimitive(const YAML::Node& node, Scene* scene);
  int MeshRef(const YAML::Node& node, const std::string& context, Scene* scene);
  std::vector<AnnotatedElement> ParseElement(const YAML::Node& node) const;
  DynamicObject ParseDynamic(const YAML::Node& node, Scene* scene);
  void ParsePaths(const YAML::Node& node, Scene* scene) const;
  SceneLighting ParseLighting(const YAML::Node& node) const;
  SceneView ParseView(const YAML::Node& node) const;
  Eigen::Vector3d ParseOrientation(const YAML::Node& node, const std::string& context) const;
  int MaterialRef(const YAML::Node& node, const std::string& key, const Scene& scene,
                  const std::string& context) const;

  SceneYaml y_;
  std::string dir_;  ///< folder of the scene file: mesh files resolve against it
};

Material SceneParser::ParseMaterial(const YAML::Node& node) const {
  y_.CheckKeys(node, {"name", "albedo", "retroreflective", "texture", "color"}, "material");
  Material m;
  m.name = y_.Get<std::string>(node, "name", "material");
  const std::string context = "material '" + m.name + "'";
  m.albedo = y_.Get<double>(node, "albedo", context);
  if (!(m.albedo >= 0.0 && m.albedo <= 1.0)) y_.Fail(node["albedo"], "albedo must be in [0, 1] in " + context);
  m.retroreflective = y_.GetOr<bool>(node, "retroreflective", false, context);
  m.texture = y_.GetOr<std::string>(node, "texture", "", context);
  m.color_rgb = node["color"] ? y_.Color(node, "color", context)
                              : Eigen::Vector3d::Constant(m.texture.empty() ? 0.7 : 1.0);
  return m;
}

TextureSpec SceneParser::ParseTexture(const YAML::Node& node) const {
  y_.CheckKeys(node, {"name", "pattern", "color_a", "color_b", "size", "cells", "grain", "resolution"}, "texture");
  TextureSpec t;
  t.name = y_.Get<std::string>(node, "name", "texture");
  const std::string context = "texture '" + t.name + "'";
  const std::string pattern = y_.Get<std::string>(node, "pattern", context);
  if (!ParseTexturePattern(pattern, &t.pattern)) y_.Fail(node["pattern"], "unknown pattern '" + pattern + "' in " + context);
  if (node["color_a"]) t.color_a = y_.Color(node, "color_a", context);
  if (node["color_b"]) t.color_b = y_.Color(node, "color_b", context);
  t.size_m = y_.GetOr<double>(node, "size", t.size_m, context);
  t.cells = y_.GetOr<int>(node, "cells", t.cells, context);
  t.grain = y_.GetOr<double>(node, "grain", t.grain, context);
  t.resolution_px = y_.GetOr<int>(node, "resolution", t.resolution_px, context);
  std::string error;
  if (!t.Validate(&error)) y_.Fail(node, error);
  return t;
}

std::vector<Copy> SceneParser::ParseRepeat(const YAML::Node& node, const std::string& context) const {
  const YAML::Node r = node["repeat"];
  if (!r) return {Copy{}};
  y_.CheckKeys(r, {"count", "step"}, "repeat of " + context);
  const YAML::Node count = r["count"], step = r["step"];
  if (!count || !count.IsSequence() || count.size() < 1 || count.size() > 3) {
    y_.Fail(r, "'count' in repeat of " + context + " must be a list of 1 to 3 integers");
  }
  const int dims = static_cast<int>(count.size());
  const Eigen::Vector3d step_m = y_.Vec(r, "step", dims, "repeat of " + context);
  int n[3] = {1, 1, 1};
  for (int d = 0; d < dims; ++d) {
    n[d] = y_.As<int>(count[d], "count", "repeat of " + context);
    if (n[d] < 1 || n[d] > 1000) y_.Fail(count[d], "'count' in repeat of " + context + " must be in [1, 1000]");
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

Eigen::Vector3d SceneParser::ParseOrientation(const YAML::Node& node, const std::string& context) const {
  if (node["yaw_deg"] && node["rpy_deg"]) y_.Fail(node, "give either yaw_deg or rpy_deg in " + context);
  if (node["rpy_deg"]) return y_.Vec(node, "rpy_deg", 3, context) * kDegToRad;
  return Eigen::Vector3d(0.0, 0.0, y_.GetOr<double>(node, "yaw_deg", 0.0, context) * kDegToRad);
}

int SceneParser::MaterialRef(const YAML::Node& node, const std::string& key, const Scene& scene,
                             const std::string& context) const {
  const std::string name = y_.Get<std::string>(node, key, context);
  const int id = scene.FindMaterial(name);
  if (id < 0) y_.Fail(node[key], "unknown material '" + name + "' in " + context);
  return id;
}

int SceneParser::MeshRef(const YAML::Node& node, const std::string& context, Scene* scene) {
  const std::string file = y_.Get<std::string>(node, "file", context);
  for (size_t i = 0; i < scene->meshes.size(); ++i) {
    if (scene->meshes[i].file == file) return static_cast<int>(i);
  }
  MeshAsset asset;
  asset.file = file;
  const std::filesystem::path p(file);
  const std::string path = p.is_absolute() ? file : (std::filesystem::path(dir_) / p).string();
  if (Status s = LoadMeshFile(path, &asset); !s) y_.Fail(node["file"], s.message + " (file in " + context + ")");
  scene->meshes.push_back(std::move(asset));
  return static_cast<int>(scene->meshes.size()) - 1;
}

Primitive SceneParser::ParsePrimitive(const YAML::Node& node, Scene* scene) {
  if (!node.IsMap()) y_.Fail(node, "primitive: expected a mapping");
  Primitive p;
  const std::string type = y_.Get<std::string>(node, "type", "primitive");
  p.name = y_.GetOr<std::string>(node, "name", type, "primitive");
  const std::string context = "primitive '" + p.name + "'";
  std::set<std::string> allowed{"type", "name", "center", "yaw_deg", "rpy_deg", "material", "repeat",
                                "hide_in_top_view"};
  if (type == "box") {
    p.type = PrimitiveType::kBox;
    allowed.insert({"size", "inward", "floor_material", "ceiling_material"});
  } else if (type == "quad" || type == "plane") {
    p.type = PrimitiveType::kQuad;
    allowed.insert("size");
  } else if (type == "cylinder") {
    p.type = PrimitiveType::kCylinder;
    allowed.insert({"radius", "height", "segments"});
  } else if (type == "mesh") {
    p.type = PrimitiveType::kMesh;
    allowed.insert({"file", "scale"});
  } else {
    y_.Fail(node["type"], "unknown primitive type '" + type + "' (box, quad, plane, cylinder, mesh) in " + context);
  }
  y_.CheckKeys(node, allowed, context);
  p.center_m = y_.Vec(node, "center", 3, context);
  p.rpy_rad = ParseOrientation(node, context);
  p.material_id = MaterialRef(node, "material", *scene, context);
  p.hide_in_top_view = y_.GetOr<bool>(node, "hide_in_top_view", false, context);
  if (p.type == PrimitiveType::kBox) {
    p.size_m = y_.Vec(node, "size", 3, context);
    p.inward = y_.GetOr<bool>(node, "inward", false, context);
    if (node["floor_material"]) p.floor_material_id = MaterialRef(node, "floor_material", *scene, context);
    if (node["ceiling_material"]) p.ceiling_material_id = MaterialRef(node, "ceiling_material", *scene, context);
  } else if (p.type == PrimitiveType::kQuad) {
    p.size_m = y_.Vec(node, "size", 2, context);
  } else if (p.type == PrimitiveType::kCylinder) {
    p.radius_m = y_.Get<double>(node, "radius", context);
    p.height_m = y_.Get<double>(node, "height", context);
    p.segments = y_.GetOr<int>(node, "segments", 24, context);
  } else {
    p.mesh_id = MeshRef(node, context, scene);
    const YAML::Node scale = node["scale"];
    if (scale && scale.IsSequence()) p.scale = y_.Vec(node, "scale", 3, context);
    if (scale && !scale.IsSequence()) p.scale = Eigen::Vector3d::Constant(y_.As<double>(scale, "scale", context));
  }
  std::string error;  // validate it here so the error carries its line
  if (!ValidatePrimitive(p, *scene, &error)) y_.Fail(node, error);
  return p;
}

std::vector<Primitive> SceneParser::ParsePrimitives(const YAML::Node& list, const std::string& context,
                                                    Scene* scene) {
  if (!list || !list.IsSequence()) y_.Fail(list, "'" + context + "' must be a list");
  std::vector<Primitive> out;
  for (const YAML::Node& node : list) {
    const Primitive p = ParsePrimitive(node, scene);
    for (const Copy& c : ParseRepeat(node, "primitive '" + p.name + "'")) {
      out.push_back(p);
      out.back().name += c.suffix;
      out.back().center_m += c.offset_m;
    }
  }
  return out;
}

std::vector<AnnotatedElement> SceneParser::ParseElement(const YAML::Node& node) const {
  y_.CheckKeys(node, {"name", "type", "center", "width", "height", "depth", "yaw_deg", "open", "primitive", "repeat"},
               "element");
  AnnotatedElement e;
  e.name = y_.Get<std::string>(node, "name", "element");
  const std::string context = "element '" + e.name + "'";
  e.type = y_.Get<std::string>(node, "type", context);
  if (e.type != "door" && e.type != "window" && e.type != "column") {
    y_.Fail(node["type"], "type must be door, window or column in " + context);
  }
  e.center_m = y_.Vec(node, "center", 3, context);
  e.width_m = y_.Get<double>(node, "width", context);
  e.height_m = y_.Get<double>(node, "height", context);
  e.depth_m = y_.GetOr<double>(node, "depth", 0.0, context);
  if (!(e.width_m > 0.0 && e.height_m > 0.0)) y_.Fail(node, "width and height must be > 0 in " + context);
  if (!(e.depth_m >= 0.0)) y_.Fail(node["depth"], "depth must be >= 0 in " + context);
  e.yaw_rad = y_.GetOr<double>(node, "yaw_deg", 0.0, context) * kDegToRad;
  e.open = y_.GetOr<bool>(node, "open", false, context);
  e.primitive = y_.GetOr<std::string>(node, "primitive", "", context);
  std::vector<AnnotatedElement> out;
  for (const Copy& c : ParseRepeat(node, context)) {
    out.push_back(e);
    out.back().name += c.suffix;
    out.back().center_m += c.offset_m;
    if (!e.primitive.empty()) out.back().primitive += c.suffix;  // copies pair with copies of the primitive
  }
  return out;
}

DynamicObject SceneParser::ParseDynamic(const YAML::Node& node, Scene* scene) {
  y_.CheckKeys(node, {"name", "kind", "material", "path", "z", "speed", "start_offset", "loop", "parts"},
               "dynamic object");
  DynamicObject o;
  o.name = y_.Get<std::string>(node, "name", "dynamic object");
  const std::string context = "dynamic object '" + o.name + "'";
  o.kind = y_.Get<std::string>(node, "kind", context);
  if (o.kind != "person" && o.kind != "car") y_.Fail(node["kind"], "kind must be person or car in " + context);
  const YAML::Node path = node["path"];
  if (!path || !path.IsSequence()) y_.Fail(node, "'path' in " + context + " must be a list of [x, y] or [x, y, z]");
  const double z_m = y_.GetOr<double>(node, "z", 0.0, context);  // ground height of 2-element waypoints
  for (const YAML::Node& w : path) {
    const bool with_z = w.IsSequence() && w.size() == 3;
    Eigen::Vector3d p = y_.VecNode(w, "path", with_z ? 3 : 2, context);
    if (!with_z) p.z() = z_m;
    o.path_m.push_back(p);
  }
  o.speed_mps = y_.Get<double>(node, "speed", context);
  o.start_offset_m = y_.GetOr<double>(node, "start_offset", 0.0, context);
  o.loop = y_.GetOr<bool>(node, "loop", true, context);
  if (node["parts"]) {
    if (node["material"]) y_.Fail(node["material"], "give either material or parts in " + context);
    o.parts = ParsePrimitives(node["parts"], "parts", scene);
  } else {
    o.parts = DefaultBody(o.kind, MaterialRef(node, "material", *scene, context));
  }
  std::string error;
  if (!ValidateDynamicObject(o, *scene, &error)) y_.Fail(node, error);
  return o;
}

void SceneParser::ParsePaths(const YAML::Node& node, Scene* scene) const {
  y_.CheckKeys(node, {"handheld", "wheeled", "car"}, "paths");
  for (const auto& kv : node) {
    const std::string carrier = kv.first.as<std::string>();
    const std::string context = "path '" + carrier + "'";
    if (!kv.second.IsSequence()) y_.Fail(kv.second, context + " must be a list of [x, y] or [x, y, dwell_s]");
    std::vector<Waypoint2d>& path = scene->default_paths[carrier];
    scene->path_order.push_back(carrier);
    for (const YAML::Node& w : kv.second) {
      const bool with_dwell = w.IsSequence() && w.size() == 3;
      const Eigen::Vector3d v = y_.VecNode(w, carrier, with_dwell ? 3 : 2, context);
      path.push_back(Waypoint2d{v.x(), v.y(), v.z()});
    }
  }
}

SceneLighting SceneParser::ParseLighting(const YAML::Node& node) const {
  y_.CheckKeys(node, {"ambient", "headlight", "sky", "lights"}, "lighting");
  SceneLighting l;
  l.ambient = y_.GetOr<double>(node, "ambient", l.ambient, "lighting");
  l.headlight = y_.GetOr<double>(node, "headlight", l.headlight, "lighting");
  if (node["sky"]) l.sky_rgb = y_.Color(node, "sky", "lighting");
  if (const YAML::Node lights = node["lights"]) {
    if (!lights.IsSequence()) y_.Fail(lights, "'lights' must be a list");
    for (const YAML::Node& n : lights) {
      y_.CheckKeys(n, {"position", "direction", "directional", "intensity", "cast_shadow"}, "light");
      SceneLight light;
      if (n["position"]) light.position_m = y_.Vec(n, "position", 3, "light");
      if (n["direction"]) light.direction = y_.Vec(n, "direction", 3, "light").normalized();
      light.directional = y_.GetOr<bool>(n, "directional", false, "light");
      light.intensity = y_.GetOr<double>(n, "intensity", light.intensity, "light");
      light.cast_shadow = y_.GetOr<bool>(n, "cast_shadow", false, "light");
      if (!(light.intensity >= 0.0 && light.intensity <= 1.0) || !light.direction.allFinite()) {
        y_.Fail(n, "light: intensity must be in [0, 1] and direction non-zero");
      }
      l.lights.push_back(light);
    }
  }
  if (!(l.ambient >= 0.0 && l.ambient <= 1.0 && l.headlight >= 0.0 && l.headlight <= 1.0)) {
    y_.Fail(node, "lighting: ambient and headlight must be in [0, 1]");
  }
  return l;
}

SceneView SceneParser::ParseView(const YAML::Node& node) const {
  y_.CheckKeys(node, {"eye", "target", "fov_deg"}, "view");
  SceneView v;
  v.set = true;
  v.eye_m = y_.Vec(node, "eye", 3, "view");
  v.target_m = y_.Vec(node, "target", 3, "view");
  v.fov_deg = y_.GetOr<double>(node, "fov_deg", v.fov_deg, "view");
  if (!(v.fov_deg > 1.0 && v.fov_deg < 170.0) || (v.eye_m - v.target_m).norm() < 1e-6) {
    y_.Fail(node, "view: fov_deg must be in (1, 170) and eye != target");
  }
  return v;
}

Scene SceneParser::Parse(const YAML::Node& root) {
  y_.CheckKeys(root, {"format_version", "name", "description", "closed", "bounds", "materials", "textures",
                      "primitives", "elements", "dynamic", "paths", "lighting", "view"},
               "scene");
  const int version = y_.Get<int>(root, "format_version", "scene");
  if (version != 1) y_.Fail(root["format_version"], "unsupported format_version " + std::to_string(version));
  Scene scene;
  scene.source_path = y_.path();
  scene.name = y_.GetOr<std::string>(root, "name", "", "scene");
  scene.description = y_.GetOr<std::string>(root, "description", "", "scene");
  scene.closed = y_.GetOr<bool>(root, "closed", false, "scene");
  const YAML::Node bounds = root["bounds"];
  if (!bounds) y_.Fail(root, "missing key 'bounds' in scene");
  y_.CheckKeys(bounds, {"min", "max"}, "bounds");
  scene.bounds = Eigen::AlignedBox3d(y_.Vec(bounds, "min", 3, "bounds"), y_.Vec(bounds, "max", 3, "bounds"));
  if (scene.bounds.isEmpty()) y_.Fail(bounds, "bounds: min must be < max");
  if (const YAML::Node textures = root["textures"]) {
    if (!textures.IsSequence()) y_.Fail(textures, "'textures' must be a list");
    for (const YAML::Node& t : textures) scene.textures.push_back(ParseTexture(t));
  }
  const YAML::Node materials = root["materials"];
  if (!materials || !materials.IsSequence()) y_.Fail(root, "'materials' must be a list");
  for (const YAML::Node& m : materials) {
    scene.materials.push_back(ParseMaterial(m));
    const Material& added = scene.materials.back();
    if (scene.FindMaterial(added.name) + 1 != static_cast<int>(scene.materials.size())) {
      y_.Fail(m, "material '" + added.name + "' defined twice");
    }
    if (!added.texture.empty() && !FindTexture(scene.textures, added.texture)) {
      y_.Fail(m["texture"], "unknown texture '" + added.texture + "' in material '" + added.name + "'");
    }
  }
  scene.primitives = ParsePrimitives(root["primitives"], "primitives", &scene);
  if (const YAML::Node elements = root["elements"]) {
    if (!elements.IsSequence()) y_.Fail(elements, "'elements' must be a list");
    for (const YAML::Node& e : elements) {
      for (AnnotatedElement& one : ParseElement(e)) scene.elements.push_back(std::move(one));
    }
  }
  if (const YAML::Node dynamic = root["dynamic"]) {
    if (!dynamic.IsSequence()) y_.Fail(dynamic, "'dynamic' must be a list");
    for (const YAML::Node& d : dynamic) scene.dynamic_objects.push_back(ParseDynamic(d, &scene));
  }
  if (root["paths"]) ParsePaths(root["paths"], &scene);
  if (root["lighting"]) scene.lighting = ParseLighting(root["lighting"]);
  if (root["view"]) scene.view = ParseView(root["view"]);
  std::string error;
  if (!scene.Validate(&error)) y_.Fail(root, error);
  return scene;
}

}  // namespace

Status LoadScene(const std::string& path, Scene* scene) {
  ROTOLIDAR_CHECK(scene != nullptr, "LoadScene needs an output");
  try {
    const YAML::Node root = yaml::LoadFile(path);
    *scene = SceneParser(path).Parse(root);
    return Status::Ok();
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  } catch (const YAML::Exception& e) {
    return Status::Error(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

}  // namespace rotolidar::sim
