// Scene file loader (docs/scene_format.md) with the project's one YAML idiom (core/io/yaml_fields.hpp): field
// lists drive the strict key checks and the reading; references (materials, textures, meshes), repeats and the
// type-dependent keys of primitives are read by the parser below. Every error names file:line and the field
// (e.g. "materials[2].albedo"); nothing throws out.
#include <cmath>
#include <filesystem>

#include "sim/world/mesh_io.hpp"
#include "sim/world/scene.hpp"
#include "sim/world/scene_dynamic.hpp"
#include "sim/world/scene_fields.hpp"
#include "core/util/log.hpp"

namespace rotolidar::sim {

const std::vector<std::pair<const char*, PrimitiveType>>& EnumWords(PrimitiveType*) {
  static const std::vector<std::pair<const char*, PrimitiveType>> words{{"box", PrimitiveType::kBox},
                                                                        {"quad", PrimitiveType::kQuad},
                                                                        {"plane", PrimitiveType::kQuad},
                                                                        {"cylinder", PrimitiveType::kCylinder},
                                                                        {"mesh", PrimitiveType::kMesh}};
  return words;
}

namespace {

using scene_io::Copy;
using scene_io::Fail;
using scene_io::ForEachItem;
using scene_io::kDegToRad;
using scene_io::ParsePaths;
using scene_io::ParseRepeat;
using scene_io::Point;
using scene_io::ReadDegrees;
using scene_io::ReadPoint;
using scene_io::ReadVec;
using yaml::Section;

class SceneParser {
 public:
  /// `chain`: the files that extend this one, outermost first (to find cycles of `extends`).
  SceneParser(const std::string& path, std::vector<std::string> chain)
      : file_(path), dir_(std::filesystem::path(path).parent_path().string()), chain_(std::move(chain)) {}

  Scene Parse(const YAML::Node& root);

 private:
  Scene LoadBase(const Section& at, const YAML::Node& extends) const;
  void ParseBody(const Section& at, const YAML::Node& root, Scene* scene);
  void ParseLook(const Section& at, const YAML::Node& root, Scene* scene) const;
  void ParseMaterials(const Section& at, const YAML::Node& list, Scene* scene) const;
  std::vector<Primitive> ParsePrimitives(const Section& at, const YAML::Node& list, Scene* scene);
  Primitive ParsePrimitive(const Section& at, const YAML::Node& node, Scene* scene);
  template <class V>
  void VisitShape(V& v, Primitive& p, Scene* scene);
  void ReadOrientation(const Section& at, const YAML::Node& node, Primitive* p) const;
  int MaterialRef(const Section& at, const YAML::Node& name, const Scene& scene) const;
  int MeshRef(const Section& at, const YAML::Node& file, Scene* scene);
  std::vector<AnnotatedElement> ParseElement(const Section& at, const YAML::Node& node) const;
  DynamicObject ParseDynamic(const Section& at, const YAML::Node& node, Scene* scene);

  std::string file_;
  std::string dir_;  ///< folder of the scene file: mesh files resolve against it
  std::vector<std::string> chain_;
  std::size_t base_materials_ = 0;  ///< materials inherited from the base scene (this file may redefine them)
};

/// The file a path names, for comparing paths (the path itself when it cannot be resolved).
std::string Canonical(const std::string& path) {
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::weakly_canonical(path, ec);
  return ec ? path : p.string();
}

void SceneParser::ParseMaterials(const Section& at, const YAML::Node& list, Scene* scene) const {
  ForEachItem(at, list, [&](const Section& item, const YAML::Node& node) {
    Material m;
    yaml::Parse(item, node, &m);
    if (!node["color"]) m.color_rgb = Eigen::Vector3d::Constant(m.texture.empty() ? 0.7 : 1.0);
    if (!(m.albedo >= 0.0 && m.albedo <= 1.0))
      Fail(item, node["albedo"], "albedo must be in [0, 1] in material '" + m.name + "'");
    if (!(m.transmittance >= 0.0 && m.transmittance < 1.0 && m.albedo + m.transmittance <= 1.0))
      Fail(item, node["transmittance"], "transmittance must be in [0, 1) with albedo + transmittance <= 1 in "
                                        "material '" + m.name + "'");
    if (!(m.specular >= 0.0 && m.albedo + m.transmittance + m.specular <= 1.0))
      Fail(item, node, "specular must be >= 0 with albedo + transmittance + specular <= 1 in material '" + m.name +
                           "'");
    const int existing = scene->FindMaterial(m.name);
    if (existing >= static_cast<int>(base_materials_)) Fail(item, node, "material '" + m.name + "' defined twice");
    if (!m.texture.empty() && !FindTexture(scene->textures, m.texture))
      Fail(item, node["texture"], "unknown texture '" + m.texture + "' in material '" + m.name + "'");
    if (existing >= 0) {
      scene->materials[static_cast<size_t>(existing)] = m;  // redefines the base's material of that name
      return;
    }
    scene->materials.push_back(m);
  });
}

int SceneParser::MaterialRef(const Section& at, const YAML::Node& name_node, const Scene& scene) const {
  std::string name;
  yaml::ReadAs(at.file, name_node, at.path, &name);
  const int id = scene.FindMaterial(name);
  if (id < 0) Fail(at, name_node, "unknown material '" + name + "' in " + at.path);
  return id;
}

int SceneParser::MeshRef(const Section& at, const YAML::Node& file_node, Scene* scene) {
  std::string file;
  yaml::ReadAs(at.file, file_node, at.path, &file);
  const std::filesystem::path p(file);
  const std::string path = p.is_absolute() ? file : (std::filesystem::path(dir_) / p).string();
  for (size_t i = 0; i < scene->meshes.size(); ++i) {
    if (scene->meshes[i].path == path) return static_cast<int>(i);
  }
  MeshAsset asset;
  asset.file = file;
  if (Status s = LoadMeshFile(path, &asset); !s) Fail(at, file_node, s.message + " (" + at.path + ")");
  scene->meshes.push_back(std::move(asset));
  return static_cast<int>(scene->meshes.size()) - 1;
}

/// yaw_deg (about z) or rpy_deg (roll, pitch, yaw), not both.
void SceneParser::ReadOrientation(const Section& at, const YAML::Node& node, Primitive* p) const {
  if (node["yaw_deg"] && node["rpy_deg"]) Fail(at, node, "give either yaw_deg or rpy_deg in " + at.path);
  if (const YAML::Node rpy = node["rpy_deg"]) p->rpy_rad = ReadVec(at.Child("rpy_deg"), rpy, 3) * kDegToRad;
  double yaw_rad = 0.0;
  if (const YAML::Node yaw = node["yaw_deg"]) ReadDegrees(at.Child("yaw_deg"), yaw, &yaw_rad);
  if (!node["rpy_deg"]) p->rpy_rad = Eigen::Vector3d(0.0, 0.0, yaw_rad);
}

/// The fields of a primitive of p.type (besides repeat and the orientation, which are read by hand).
template <class V>
void SceneParser::VisitShape(V& v, Primitive& p, Scene* scene) {
  const auto material = [this, scene](const Section& at, const YAML::Node& n, int* id) {
    *id = MaterialRef(at, n, *scene);
  };
  const auto mesh = [this, scene](const Section& at, const YAML::Node& n, int* id) { *id = MeshRef(at, n, scene); };
  const auto scale = [](const Section& at, const YAML::Node& n, Eigen::Vector3d* s) {
    if (n.IsSequence()) return ReadPoint(at, n, s);
    double k = 1.0;
    yaml::ReadAs(at.file, n, at.path, &k);
    *s = Eigen::Vector3d::Constant(k);
  };
  v("type", &p.type), v("name", &p.name), v("center", yaml::Required(Point(&p.center_m)));
  v("material", yaml::Required(yaml::Custom(&p.material_id, material)));
  v("hide_in_top_view", &p.hide_in_top_view);
  if (p.type == PrimitiveType::kBox) {
    v("size", yaml::Required(Point(&p.size_m))), v("inward", &p.inward);
    v("floor_material", yaml::Custom(&p.floor_material_id, material));
    v("ceiling_material", yaml::Custom(&p.ceiling_material_id, material));
  } else if (p.type == PrimitiveType::kQuad) {
    const auto size2 = [](const Section& at, const YAML::Node& n, Eigen::Vector3d* s) { *s = ReadVec(at, n, 2); };
    v("size", yaml::Required(yaml::Custom(&p.size_m, size2)));
  } else if (p.type == PrimitiveType::kCylinder) {
    v("radius", yaml::Required(&p.radius_m)), v("height", yaml::Required(&p.height_m)), v("segments", &p.segments);
  } else {
    v("file", yaml::Required(yaml::Custom(&p.mesh_id, mesh))), v("scale", yaml::Custom(&p.scale, scale));
  }
}

Primitive SceneParser::ParsePrimitive(const Section& at, const YAML::Node& node, Scene* scene) {
  if (!node.IsMap()) Fail(at, node, at.path + ": expected a mapping");
  Primitive p;
  yaml::Parser read{at, node};
  std::string type;
  read("type", yaml::Required(&type));
  read("type", &p.type);
  p.name = type;  // the default name: the type as written
  yaml::KeyCollector keys{{"yaw_deg", "rpy_deg", "repeat"}};
  VisitShape(keys, p, scene);
  yaml::CheckKeys(at.file, node, keys.keys, at.path);
  ReadOrientation(at, node, &p);
  VisitShape(read, p, scene);
  std::string error;  // validate it here so the error carries its line
  if (!ValidatePrimitive(p, *scene, &error)) Fail(at, node, error);
  return p;
}

std::vector<Primitive> SceneParser::ParsePrimitives(const Section& at, const YAML::Node& list, Scene* scene) {
  std::vector<Primitive> out;
  ForEachItem(at, list, [&](const Section& item, const YAML::Node& node) {
    const Primitive p = ParsePrimitive(item, node, scene);
    for (const Copy& c : ParseRepeat(item, node)) {
      out.push_back(p);
      out.back().name += c.suffix;
      out.back().center_m += c.offset_m;
    }
  });
  return out;
}

std::vector<AnnotatedElement> SceneParser::ParseElement(const Section& at, const YAML::Node& node) const {
  AnnotatedElement e;
  yaml::Parse(at, node, &e, {"repeat"});
  const std::string context = " in element '" + e.name + "'";
  if (e.type != "door" && e.type != "window" && e.type != "column")
    Fail(at, node["type"], "type must be door, window or column" + context);
  if (!(e.width_m > 0.0 && e.height_m > 0.0)) Fail(at, node, "width and height must be > 0" + context);
  if (!(e.depth_m >= 0.0)) Fail(at, node["depth"], "depth must be >= 0" + context);
  std::vector<AnnotatedElement> out;
  for (const Copy& c : ParseRepeat(at, node)) {
    out.push_back(e);
    out.back().name += c.suffix;
    out.back().center_m += c.offset_m;
    if (!e.primitive.empty()) out.back().primitive += c.suffix;  // copies pair with copies of the primitive
  }
  return out;
}

DynamicObject SceneParser::ParseDynamic(const Section& at, const YAML::Node& node, Scene* scene) {
  DynamicObject o;
  yaml::Parse(at, node, &o, {"material", "path", "z", "parts"});
  const std::string context = " in dynamic object '" + o.name + "'";
  if (o.kind != "person" && o.kind != "car") Fail(at, node["kind"], "kind must be person or car" + context);
  const YAML::Node path = node["path"];
  if (!path || !path.IsSequence()) Fail(at, node, "'path' must be a list of [x, y] or [x, y, z]" + context);
  double z_m = 0.0;  // ground height of 2-element waypoints
  yaml::Parser{at, node}("z", &z_m);
  ForEachItem(at.Child("path"), path, [&](const Section& item, const YAML::Node& w) {
    const bool with_z = w.IsSequence() && w.size() == 3;
    Eigen::Vector3d p = ReadVec(item, w, with_z ? 3 : 2);
    if (!with_z) p.z() = z_m;
    o.path_m.push_back(p);
  });
  if (const YAML::Node parts = node["parts"]) {
    if (node["material"]) Fail(at, node["material"], "give either material or parts" + context);
    o.parts = ParsePrimitives(at.Child("parts"), parts, scene);
  } else {
    if (!node["material"]) Fail(at, node, "missing required key 'material' in " + at.path);
    o.parts = DefaultBody(o.kind, MaterialRef(at.Child("material"), node["material"], *scene));
  }
  std::string error;
  if (!ValidateDynamicObject(o, *scene, &error)) Fail(at, node, error);
  return o;
}

/// The scene `extends` names: <dir>/<name>.yaml, or <dir>/<name> when it already ends in .yaml.
Scene SceneParser::LoadBase(const Section& at, const YAML::Node& extends) const {
  std::string name;
  yaml::ReadAs(file_, extends, "extends", &name);
  std::filesystem::path p(name);
  if (p.extension() != ".yaml") p += ".yaml";
  const std::string path = p.is_absolute() ? p.string() : (std::filesystem::path(dir_) / p).string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) Fail(at, extends, "base scene '" + path + "' not found (extends)");
  std::vector<std::string> chain = chain_;
  chain.push_back(Canonical(file_));
  const std::string base = Canonical(path);
  for (const std::string& f : chain) {
    if (f != base) continue;
    std::string cycle;
    for (const std::string& c : chain) cycle += c + " -> ";
    Fail(at, extends, "extends cycle: " + cycle + base);
  }
  try {
    return SceneParser(path, chain).Parse(yaml::LoadFile(path));
  } catch (const yaml::ParseError& e) {
    Fail(at, extends, std::string("in base scene (extends): ") + e.what());
  } catch (const YAML::Exception& e) {
    Fail(at, extends, "in base scene (extends): " + path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

Scene SceneParser::Parse(const YAML::Node& root) {
  const Section at(file_, "", "scene");
  if (!root.IsMap()) Fail(at, root, "a scene file must be a mapping");
  yaml::CheckKeys(file_, root, {"format_version", "extends", "name", "description", "closed", "bounds", "materials",
                                "textures", "primitives", "elements", "dynamic", "paths", "lighting", "view"},
                  "scene");
  int version = 0;
  yaml::Parser read{at, root};
  read("format_version", yaml::Required(&version));
  if (version != 1) Fail(at, root["format_version"], "unsupported format_version " + std::to_string(version));
  Scene scene;
  if (const YAML::Node extends = root["extends"]) {
    scene = LoadBase(at.Child("extends"), extends);
    base_materials_ = scene.materials.size();
  } else {
    for (const char* key : {"bounds", "materials", "primitives"}) {
      if (!root[key]) Fail(at, root, std::string("missing required key '") + key + "' in scene");
    }
  }
  scene.source_path = file_;
  ParseBody(at, root, &scene);
  std::string error;
  if (!scene.Validate(&error)) Fail(at, root, error);
  return scene;
}

/// Reads every key but format_version and extends over *scene (empty, or the base scene: lists append, paths
/// replace per carrier, materials of the base's names redefine them, the other keys replace).
void SceneParser::ParseBody(const Section& at, const YAML::Node& root, Scene* out) {
  Scene& scene = *out;
  yaml::Parser read{at, root};
  read("name", &scene.name), read("description", &scene.description), read("closed", &scene.closed);
  if (const YAML::Node bounds = root["bounds"]) {
    Eigen::Vector3d lo, hi;
    yaml::CheckKeys(file_, bounds, {"min", "max"}, "bounds");
    yaml::Parser read_bounds{at.Child("bounds"), bounds};
    read_bounds("min", yaml::Required(Point(&lo))), read_bounds("max", yaml::Required(Point(&hi)));
    scene.bounds = Eigen::AlignedBox3d(lo, hi);
    if (scene.bounds.isEmpty()) Fail(at, bounds, "bounds: min must be < max");
  }
  if (const YAML::Node textures = root["textures"]) {
    ForEachItem(at.Child("textures"), textures, [&](const Section& item, const YAML::Node& node) {
      TextureSpec t;
      yaml::Parse(item, node, &t);
      std::string error;
      if (!t.Validate(&error)) Fail(item, node, error);
      scene.textures.push_back(t);
    });
  }
  if (const YAML::Node materials = root["materials"]) ParseMaterials(at.Child("materials"), materials, &scene);
  if (const YAML::Node primitives = root["primitives"]) {
    for (Primitive& p : ParsePrimitives(at.Child("primitives"), primitives, &scene))
      scene.primitives.push_back(std::move(p));
  }
  const auto unique = [&](const Section& item, const YAML::Node& node, const std::string& what, const auto& list,
                          std::size_t before) {
    for (std::size_t i = 0; i < before; ++i) {
      if (list[i].name == list.back().name) Fail(item, node, what + " '" + list.back().name + "' defined twice");
    }
  };
  if (const YAML::Node elements = root["elements"]) {
    ForEachItem(at.Child("elements"), elements, [&](const Section& item, const YAML::Node& node) {
      const std::size_t before = scene.elements.size();
      for (AnnotatedElement& one : ParseElement(item, node)) {
        scene.elements.push_back(std::move(one));
        unique(item, node, "element", scene.elements, before);
      }
    });
  }
  if (const YAML::Node dynamic = root["dynamic"]) {
    ForEachItem(at.Child("dynamic"), dynamic, [&](const Section& item, const YAML::Node& node) {
      const std::size_t before = scene.dynamic_objects.size();
      scene.dynamic_objects.push_back(ParseDynamic(item, node, &scene));
      unique(item, node, "dynamic object", scene.dynamic_objects, before);
    });
  }
  if (const YAML::Node paths = root["paths"]) ParsePaths(at.Child("paths"), paths, &scene);
  ParseLook(at, root, &scene);
}

/// `lighting` and `view`, each replacing the scene's (the base's) as a whole when present.
void SceneParser::ParseLook(const Section& at, const YAML::Node& root, Scene* out) const {
  Scene& scene = *out;
  if (const YAML::Node lighting = root["lighting"]) {
    scene.lighting = SceneLighting{};
    yaml::ReadValue(at.Child("lighting"), lighting, &scene.lighting);
    const SceneLighting& l = scene.lighting;
    if (!(l.ambient >= 0.0 && l.ambient <= 1.0 && l.headlight >= 0.0 && l.headlight <= 1.0))
      Fail(at, lighting, "lighting: ambient and headlight must be in [0, 1]");
  }
  if (const YAML::Node view = root["view"]) {
    scene.view = SceneView{};
    yaml::ReadValue(at.Child("view"), view, &scene.view);
    const SceneView& v = scene.view;
    scene.view.set = true;
    if (!(v.fov_deg > 1.0 && v.fov_deg < 170.0) || (v.eye_m - v.target_m).norm() < 1e-6)
      Fail(at, view, "view: fov_deg must be in (1, 170) and eye != target");
  }
}

}  // namespace

Status LoadScene(const std::string& path, Scene* scene) {
  ROTOLIDAR_CHECK(scene != nullptr, "LoadScene needs an output");
  try {
    const YAML::Node root = yaml::LoadFile(path);
    *scene = SceneParser(path, {}).Parse(root);
    return Status::Ok();
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  } catch (const YAML::Exception& e) {
    return Status::Error(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

}  // namespace rotolidar::sim
