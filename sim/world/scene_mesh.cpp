// Scene validation and tessellation into the shared triangle mesh (static world, dynamic objects posed at t).
#include <cmath>
#include <sstream>

#include "core/util/log.hpp"
#include "core/util/validation.hpp"
#include "sim/world/scene.hpp"
#include "sim/world/scene_dynamic.hpp"

namespace rotolidar::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

bool ValidMaterialRef(int id, const std::vector<Material>& materials, bool optional) {
  if (optional && id == -1) return true;
  return id >= 0 && id < static_cast<int>(materials.size());
}

bool CheckPrimitive(const Primitive& p, const std::vector<Material>& materials, std::size_t num_meshes,
                    std::string* error) {
  const std::string where = "primitive '" + p.name + "': ";
  if (!p.center_m.allFinite() || !p.rpy_rad.allFinite()) return FailValidation(error, where + "non-finite center/rpy");
  if (!ValidMaterialRef(p.material_id, materials, false) || !ValidMaterialRef(p.floor_material_id, materials, true) ||
      !ValidMaterialRef(p.ceiling_material_id, materials, true)) {
    return FailValidation(error, where + "unknown material");
  }
  switch (p.type) {
    case PrimitiveType::kBox:
      if (!(p.size_m.minCoeff() > 0.0)) return FailValidation(error, where + "size must be > 0");
      break;
    case PrimitiveType::kQuad:
      if (!(p.size_m.x() > 0.0 && p.size_m.y() > 0.0)) return FailValidation(error, where + "size must be > 0");
      break;
    case PrimitiveType::kCylinder:
      if (!(p.radius_m > 0.0)) return FailValidation(error, where + "radius must be > 0");
      if (!(p.height_m > 0.0)) return FailValidation(error, where + "height must be > 0");
      if (p.segments < 3 || p.segments > 1024) return FailValidation(error, where + "segments must be in [3, 1024]");
      break;
    case PrimitiveType::kMesh:
      if (p.mesh_id < 0 || p.mesh_id >= static_cast<int>(num_meshes))
        return FailValidation(error, where + "unknown mesh");
      if (!(p.scale.minCoeff() > 0.0) || !p.scale.allFinite())
        return FailValidation(error, where + "scale must be > 0");
      break;
  }
  return true;
}

bool ValidateMaterial(const Material& m, const std::vector<TextureSpec>& textures, std::string* error) {
  const std::string where = "material '" + m.name + "': ";
  if (!(m.albedo >= 0.0 && m.albedo <= 1.0)) return FailValidation(error, where + "albedo not in [0, 1]");
  if (!(m.transmittance >= 0.0 && m.transmittance < 1.0))
    return FailValidation(error, where + "transmittance not in [0, 1)");
  if (!(m.specular >= 0.0)) return FailValidation(error, where + "specular below 0");
  if (m.albedo + m.transmittance + m.specular > 1.0)
    return FailValidation(error, where + "albedo + transmittance + specular exceeds 1");
  if (!(m.color_rgb.minCoeff() >= 0.0 && m.color_rgb.maxCoeff() <= 1.0)) {
    return FailValidation(error, where + "color entries not in [0, 1]");
  }
  if (!m.texture.empty() && !FindTexture(textures, m.texture)) {
    return FailValidation(error, where + "unknown texture '" + m.texture + "'");
  }
  return true;
}

bool ValidateElement(const AnnotatedElement& e, std::string* error) {
  const std::string where = "element '" + e.name + "': ";
  if (e.type != "door" && e.type != "window" && e.type != "column") {
    return FailValidation(error, where + "type must be door, window or column");
  }
  if (!(e.width_m > 0.0 && e.height_m > 0.0)) return FailValidation(error, where + "width/height <= 0");
  if (!(e.depth_m >= 0.0) || !e.center_m.allFinite() || !std::isfinite(e.yaw_rad)) {
    return FailValidation(error, where + "depth < 0 or non-finite pose");
  }
  return true;
}

bool ValidatePath(const std::string& carrier, const std::vector<Waypoint2d>& path, const Eigen::AlignedBox3d& bounds,
                  std::string* error) {
  const std::string where = "path '" + carrier + "': ";
  if (carrier != "handheld" && carrier != "wheeled" && carrier != "car") {
    return FailValidation(error, where + "carrier must be handheld, wheeled or car");
  }
  if (path.size() < 2) return FailValidation(error, where + "needs >= 2 waypoints");
  for (size_t i = 0; i < path.size(); ++i) {
    const Waypoint2d& w = path[i];
    const Eigen::Vector2d xy(w.x_m, w.y_m);
    if (!xy.allFinite() || !(w.dwell_s >= 0.0))
      return FailValidation(error, where + "waypoint " + std::to_string(i) + " bad");
    if ((xy.array() < bounds.min().head<2>().array()).any() || (xy.array() > bounds.max().head<2>().array()).any()) {
      return FailValidation(error, where + "waypoint " + std::to_string(i) + " is outside the bounds");
    }
  }
  return true;
}

bool ValidateLighting(const SceneLighting& l, std::string* error) {
  const auto unit = [](double x) { return x >= 0.0 && x <= 1.0; };
  if (!unit(l.ambient) || !unit(l.headlight)) return FailValidation(error, "lighting: ambient/headlight not in [0, 1]");
  if (!(l.sky_rgb.minCoeff() >= 0.0 && l.sky_rgb.maxCoeff() <= 1.0))
    return FailValidation(error, "lighting: sky not in [0, 1]");
  for (const SceneLight& light : l.lights) {
    if (!unit(light.intensity) || !(light.direction.norm() > 1e-9) || !light.position_m.allFinite()) {
      return FailValidation(error, "lighting: a light has intensity outside [0, 1], no direction or a bad position");
    }
  }
  return true;
}

void AppendQuad(const Primitive& p, int primitive_id, TriangleMesh* mesh) {
  const Eigen::Matrix3d R = p.Rotation();
  const Eigen::Vector3d ex = R.col(0) * (0.5 * p.size_m.x()), ey = R.col(1) * (0.5 * p.size_m.y());
  const int base = static_cast<int>(mesh->vertices_m.size());
  mesh->vertices_m.push_back(p.center_m - ex - ey);
  mesh->vertices_m.push_back(p.center_m + ex - ey);
  mesh->vertices_m.push_back(p.center_m + ex + ey);
  mesh->vertices_m.push_back(p.center_m - ex + ey);
  // Front side = local +z.
  mesh->AddTriangle(base, base + 1, base + 2, p.material_id, primitive_id);
  mesh->AddTriangle(base, base + 2, base + 3, p.material_id, primitive_id);
}

void AppendMeshAsset(const Primitive& p, const MeshAsset& asset, int primitive_id, TriangleMesh* mesh) {
  const Eigen::Matrix3d R = p.Rotation();
  const int base = static_cast<int>(mesh->vertices_m.size());
  for (const Eigen::Vector3d& v : asset.vertices_m) mesh->vertices_m.push_back(p.center_m + R * p.scale.cwiseProduct(v));
  for (const Eigen::Vector3i& t : asset.triangles) {
    mesh->AddTriangle(base + t[0], base + t[1], base + t[2], p.material_id, primitive_id);
  }
}

void AppendCylinder(const Primitive& p, int primitive_id, TriangleMesh* mesh) {
  const Eigen::Matrix3d R = p.Rotation();
  const Eigen::Vector3d half_axis = R.col(2) * (0.5 * p.height_m);
  const int n = p.segments;
  const int base = static_cast<int>(mesh->vertices_m.size());
  for (int k = 0; k < n; ++k) {  // ring vertices: bottom 2k, top 2k+1
    const double a = 2.0 * kPi * k / n;
    const Eigen::Vector3d radial = R * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0) * p.radius_m;
    mesh->vertices_m.push_back(p.center_m + radial - half_axis);
    mesh->vertices_m.push_back(p.center_m + radial + half_axis);
  }
  const int bottom_center = base + 2 * n, top_center = base + 2 * n + 1;
  mesh->vertices_m.push_back(p.center_m - half_axis);
  mesh->vertices_m.push_back(p.center_m + half_axis);
  for (int k = 0; k < n; ++k) {
    const int b0 = base + 2 * k, t0 = b0 + 1;
    const int b1 = base + 2 * ((k + 1) % n), t1 = b1 + 1;
    mesh->AddTriangle(b0, b1, t1, p.material_id, primitive_id);  // side, facing outward
    mesh->AddTriangle(b0, t1, t0, p.material_id, primitive_id);
    mesh->AddTriangle(t0, t1, top_center, p.material_id, primitive_id);     // top cap, facing +axis
    mesh->AddTriangle(b1, b0, bottom_center, p.material_id, primitive_id);  // bottom cap, facing -axis
  }
}

}  // namespace

Eigen::Matrix3d Primitive::Rotation() const {
  return (Eigen::AngleAxisd(rpy_rad.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy_rad.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy_rad.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

bool ValidatePrimitive(const Primitive& primitive, const Scene& scene, std::string* error) {
  return CheckPrimitive(primitive, scene.materials, scene.meshes.size(), error);
}

int Scene::FindMaterial(const std::string& material_name) const {
  for (size_t i = 0; i < materials.size(); ++i) {
    if (materials[i].name == material_name) return static_cast<int>(i);
  }
  return -1;
}

Eigen::Isometry3d AnnotatedElement::T_world_element() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = center_m;
  return T;
}

bool Scene::Validate(std::string* error) const {
  if (materials.empty()) return FailValidation(error, "scene has no materials");
  for (size_t i = 0; i < materials.size(); ++i) {
    if (!ValidateMaterial(materials[i], textures, error)) return false;
    for (size_t j = 0; j < i; ++j) {
      if (materials[j].name == materials[i].name) {
        return FailValidation(error, "material '" + materials[i].name + "' defined twice");
      }
    }
  }
  for (const TextureSpec& t : textures) {
    if (!t.Validate(error)) return false;
  }
  if (primitives.empty()) return FailValidation(error, "scene has no primitives");
  for (const MeshAsset& m : meshes) {
    if (m.triangles.empty()) return FailValidation(error, "mesh '" + m.file + "' has no triangles");
  }
  for (const Primitive& p : primitives) {
    if (!CheckPrimitive(p, materials, meshes.size(), error)) return false;
  }
  if (bounds.isEmpty()) return FailValidation(error, "bounds: min must be < max");
  for (const AnnotatedElement& e : elements) {
    if (!ValidateElement(e, error)) return false;
  }
  for (const DynamicObject& o : dynamic_objects) {
    if (!ValidateDynamicObject(o, *this, error)) return false;
  }
  for (const auto& [carrier, path] : default_paths) {
    if (!ValidatePath(carrier, path, bounds, error)) return false;
  }
  return ValidateLighting(lighting, error);
}

void TriangleMesh::AddTriangle(int a, int b, int c, int material_id, int primitive_id) {
  triangles.emplace_back(a, b, c);
  material_ids.push_back(material_id);
  primitive_ids.push_back(primitive_id);
}

void AppendBox(const Eigen::Vector3d& center_m, const Eigen::Matrix3d& R_world_box, const Eigen::Vector3d& size_m,
               bool inward, const std::array<int, 6>& face_materials, int primitive_id, TriangleMesh* mesh) {
  // Face f has outward normal along axis f/2 with sign (f%2 ? + : -); its two in-plane axes u, v are chosen so
  // that u x v = the outward normal (counter-clockwise seen from outside).
  for (int f = 0; f < 6; ++f) {
    const int axis = f / 2;
    const double sign = (f % 2) ? 1.0 : -1.0;
    const int u_axis = (axis + 1) % 3, v_axis = (axis + 2) % 3;
    Eigen::Vector3d n = Eigen::Vector3d::Zero(), u = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
    n[axis] = sign * 0.5 * size_m[axis];
    u[u_axis] = sign * 0.5 * size_m[u_axis];  // flipping u with the sign keeps u x v along n
    v[v_axis] = 0.5 * size_m[v_axis];
    const int base = static_cast<int>(mesh->vertices_m.size());
    for (const auto& [su, sv] : {std::pair{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}}) {
      mesh->vertices_m.push_back(center_m + R_world_box * (n + su * u + sv * v));
    }
    if (inward) {
      mesh->AddTriangle(base, base + 2, base + 1, face_materials[f], primitive_id);
      mesh->AddTriangle(base, base + 3, base + 2, face_materials[f], primitive_id);
    } else {
      mesh->AddTriangle(base, base + 1, base + 2, face_materials[f], primitive_id);
      mesh->AddTriangle(base, base + 2, base + 3, face_materials[f], primitive_id);
    }
  }
}

Primitive MakeRoom(const std::string& name, const Eigen::Vector3d& center_m, const Eigen::Vector3d& size_m,
                   int material_id) {
  Primitive p;
  p.type = PrimitiveType::kBox;
  p.name = name;
  p.center_m = center_m;
  p.size_m = size_m;
  p.inward = true;
  p.material_id = material_id;
  return p;
}

void AppendPrimitives(const std::vector<Primitive>& primitives, const std::vector<MeshAsset>& meshes,
                      TriangleMesh* mesh) {
  for (size_t i = 0; i < primitives.size(); ++i) {
    const Primitive& p = primitives[i];
    ROTOLIDAR_CHECK(p.material_id >= 0 && p.material_id < static_cast<int>(mesh->materials.size()),
                    "primitive '" << p.name << "' has material id " << p.material_id);
    const int id = static_cast<int>(i);
    switch (p.type) {
      case PrimitiveType::kBox: {
        const int floor = p.floor_material_id >= 0 ? p.floor_material_id : p.material_id;
        const int ceiling = p.ceiling_material_id >= 0 ? p.ceiling_material_id : p.material_id;
        const std::array<int, 6> faces{p.material_id, p.material_id, p.material_id, p.material_id, floor, ceiling};
        AppendBox(p.center_m, p.Rotation(), p.size_m, p.inward, faces, id, mesh);
        break;
      }
      case PrimitiveType::kQuad: AppendQuad(p, id, mesh); break;
      case PrimitiveType::kCylinder: AppendCylinder(p, id, mesh); break;
      case PrimitiveType::kMesh:
        ROTOLIDAR_CHECK(p.mesh_id >= 0 && p.mesh_id < static_cast<int>(meshes.size()),
                        "primitive '" << p.name << "' has mesh id " << p.mesh_id);
        AppendMeshAsset(p, meshes[static_cast<size_t>(p.mesh_id)], id, mesh);
        break;
    }
  }
}

TriangleMesh BuildMesh(const Scene& scene) {
  TriangleMesh mesh;
  mesh.materials = scene.materials;
  AppendPrimitives(scene.primitives, scene.meshes, &mesh);
  return mesh;
}

TriangleMesh BuildMeshAt(const Scene& scene, Seconds t) {
  TriangleMesh mesh = BuildMesh(scene);
  for (size_t k = 0; k < scene.dynamic_objects.size(); ++k) {
    const DynamicObject& object = scene.dynamic_objects[k];
    const TriangleMesh body = BuildObjectMesh(scene, object);
    const Eigen::Isometry3d T_world_body = DynamicObjectPose(object, t);
    const int base = static_cast<int>(mesh.vertices_m.size());
    for (const Eigen::Vector3d& v : body.vertices_m) mesh.vertices_m.push_back(T_world_body * v);
    for (size_t i = 0; i < body.triangles.size(); ++i) {
      const Eigen::Vector3i& tri = body.triangles[i];
      mesh.AddTriangle(base + tri[0], base + tri[1], base + tri[2], body.material_ids[i], -1 - static_cast<int>(k));
    }
  }
  return mesh;
}

Eigen::AlignedBox3d TriangleMesh::Bounds() const {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& v : vertices_m) box.extend(v);
  return box;
}

}  // namespace rotolidar::sim
