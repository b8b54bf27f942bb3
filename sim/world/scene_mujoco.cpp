// Scene -> MJCF (planes for flat faces, meshes for curved ones), compiled through MuJoCo's virtual file system.
#include "sim/world/scene_mujoco.hpp"

#include <algorithm>
#include <cstring>
#include <iomanip>
#include <map>
#include <sstream>

#include "sim/world/scene_dynamic.hpp"
#include "core/util/log.hpp"

namespace rotolidar::sim {
namespace {

/// A rectangle: centre, unit axes (front normal = x_axis cross y_axis), half extents.
struct Face {
  Eigen::Vector3d center, x_axis, y_axis;
  double half_x, half_y;
  int material_id, group;
};

std::string Vec(const Eigen::Vector3d& v) {
  std::ostringstream os;
  os << std::setprecision(12) << v.x() << " " << v.y() << " " << v.z();
  return os.str();
}

std::string Quat(const Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(R);
  std::ostringstream os;
  os << std::setprecision(15) << q.w() << " " << q.x() << " " << q.y() << " " << q.z();
  return os.str();
}

/// The faces of a box as TriangleMesh/AppendBox emits them (front = outside, or inside when inward).
std::vector<Face> BoxFaces(const Primitive& p) {
  const Eigen::Matrix3d R = p.Rotation();
  const int floor = p.floor_material_id >= 0 ? p.floor_material_id : p.material_id;
  const int ceiling = p.ceiling_material_id >= 0 ? p.ceiling_material_id : p.material_id;
  std::vector<Face> faces;
  for (int f = 0; f < 6; ++f) {
    const int axis = f / 2, u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double sign = (f % 2) ? 1.0 : -1.0;
    Face face;
    face.center = p.center_m + R.col(axis) * (sign * 0.5 * p.size_m[axis]);
    face.x_axis = R.col(u) * sign;
    face.y_axis = R.col(v);
    face.half_x = 0.5 * p.size_m[u];
    face.half_y = 0.5 * p.size_m[v];
    face.material_id = f == 4 ? floor : f == 5 ? ceiling : p.material_id;
    const bool is_ceiling = p.inward && f == 5;
    face.group = (p.hide_in_top_view || is_ceiling) ? kGeomGroupCeiling : kGeomGroupVisible;
    if (p.inward) {  // front faces inside: swap the axes to flip the normal
      std::swap(face.x_axis, face.y_axis);
      std::swap(face.half_x, face.half_y);
    }
    faces.push_back(face);
  }
  return faces;
}

Face QuadFace(const Primitive& p) {
  const Eigen::Matrix3d R = p.Rotation();
  return Face{p.center_m, R.col(0), R.col(1), 0.5 * p.size_m.x(), 0.5 * p.size_m.y(), p.material_id,
              p.hide_in_top_view ? kGeomGroupCeiling : kGeomGroupVisible};
}

Face Flipped(const Face& f, int group) {
  return Face{f.center, f.y_axis, f.x_axis, f.half_y, f.half_x, f.material_id, group};
}

class MjcfWriter {
 public:
  MjcfWriter(const Scene& scene, std::vector<GeomSource>* sources) : scene_(scene), sources_(sources) {}

  std::string Write();

 private:
  void WriteAssets();
  void WriteLighting();
  void WritePrimitive(const Primitive& p, GeomSource source);
  void WritePlane(const Face& f, GeomSource source);
  /// The mesh asset for a cylinder or mesh primitive in its own frame (deduplicated), returns its name.
  std::string MeshAsset(const Primitive& p);

  const Scene& scene_;
  std::vector<GeomSource>* sources_;
  std::ostringstream body_, assets_;
  std::map<std::string, std::string> mesh_names_;  ///< shape key -> asset name
};

std::string MjcfWriter::MeshAsset(const Primitive& p) {
  std::ostringstream key;
  key << std::setprecision(17) << static_cast<int>(p.type) << "|" << p.radius_m << "|" << p.height_m << "|"
      << p.segments << "|" << p.mesh_id << "|" << p.scale.transpose();
  const auto found = mesh_names_.find(key.str());
  if (found != mesh_names_.end()) return found->second;
  const std::string name = "mesh" + std::to_string(mesh_names_.size());
  mesh_names_[key.str()] = name;
  Primitive local = p;  // the same tessellation, in the primitive's frame
  local.center_m.setZero();
  local.rpy_rad.setZero();
  TriangleMesh mesh;
  mesh.materials.resize(static_cast<std::size_t>(p.material_id) + 1);
  AppendPrimitives({local}, scene_.meshes, &mesh);
  assets_ << "    <mesh name=\"" << name << "\" vertex=\"" << std::setprecision(12);
  for (const Eigen::Vector3d& v : mesh.vertices_m) assets_ << v.x() << " " << v.y() << " " << v.z() << " ";
  assets_ << "\" face=\"";
  for (const Eigen::Vector3i& t : mesh.triangles) assets_ << t[0] << " " << t[1] << " " << t[2] << " ";
  assets_ << "\"/>\n";
  return name;
}

void MjcfWriter::WritePlane(const Face& f, GeomSource source) {
  // The third size is the grid spacing MuJoCo draws the plane with: <= 20 x 20 cells per plane.
  const double grid = std::max(1.0, std::max(f.half_x, f.half_y) / 10.0);
  body_ << "    <geom type=\"plane\" pos=\"" << Vec(f.center) << "\" xyaxes=\"" << Vec(f.x_axis) << " "
        << Vec(f.y_axis) << "\" size=\"" << std::setprecision(12) << f.half_x << " " << f.half_y << " " << grid
        << "\" material=\"mat" << f.material_id << "\" group=\"" << f.group << "\"/>\n";
  if (sources_) sources_->push_back(source);
}

void MjcfWriter::WritePrimitive(const Primitive& p, GeomSource source) {
  switch (p.type) {
    case PrimitiveType::kBox:
      for (const Face& f : BoxFaces(p)) {
        WritePlane(f, source);
        WritePlane(Flipped(f, kGeomGroupBackside), source);
      }
      break;
    case PrimitiveType::kQuad: {
      const Face f = QuadFace(p);
      WritePlane(f, source);
      WritePlane(Flipped(f, f.group), source);  // a quad is visible from both sides
      break;
    }
    case PrimitiveType::kCylinder:
    case PrimitiveType::kMesh:
      body_ << "    <geom type=\"mesh\" mesh=\"" << MeshAsset(p) << "\" pos=\"" << Vec(p.center_m) << "\" quat=\""
            << Quat(p.Rotation()) << "\" material=\"mat" << p.material_id << "\" group=\""
            << (p.hide_in_top_view ? kGeomGroupCeiling : kGeomGroupVisible) << "\"/>\n";
      if (sources_) sources_->push_back(source);
      break;
  }
}

void MjcfWriter::WriteAssets() {
  const Eigen::Vector3d sky = scene_.lighting.sky_rgb;
  assets_ << "    <texture name=\"sky\" type=\"skybox\" builtin=\"gradient\" rgb1=\"" << Vec(sky) << "\" rgb2=\""
          << Vec(sky * 0.6) << "\" width=\"64\" height=\"64\"/>\n";
  std::map<std::string, bool> written;
  for (std::size_t i = 0; i < scene_.materials.size(); ++i) {
    const Material& m = scene_.materials[i];
    assets_ << "    <material name=\"mat" << i << "\" rgba=\"" << Vec(m.color_rgb) << " 1\" specular=\"0.1\""
            << " shininess=\"0.1\"";
    if (const TextureSpec* t = m.texture.empty() ? nullptr : FindTexture(scene_.textures, m.texture)) {
      const double repeat = 1.0 / t->size_m;
      assets_ << " texture=\"tex_" << t->name << "\" texuniform=\"true\" texrepeat=\"" << repeat << " " << repeat
              << "\"";
      if (!written[t->name]) {
        written[t->name] = true;
        assets_ << "/>\n    <texture name=\"tex_" << t->name << "\" type=\"2d\" builtin=\"flat\" width=\""
                << t->resolution_px << "\" height=\"" << t->resolution_px << "\" rgb1=\"1 1 1\"";
      }
    }
    assets_ << "/>\n";
  }
}

void MjcfWriter::WriteLighting() {
  const SceneLighting& l = scene_.lighting;
  for (const SceneLight& light : l.lights) {
    body_ << "    <light pos=\"" << Vec(light.position_m) << "\" dir=\"" << Vec(light.direction)
          << "\" directional=\"" << (light.directional ? "true" : "false") << "\" diffuse=\""
          << Vec(Eigen::Vector3d::Constant(light.intensity)) << "\" specular=\"0.05 0.05 0.05\" castshadow=\""
          << (light.cast_shadow ? "true" : "false") << "\" attenuation=\"1 0 0\"/>\n";
  }
}

std::string MjcfWriter::Write() {
  WriteAssets();
  WriteLighting();
  for (std::size_t i = 0; i < scene_.primitives.size(); ++i) {
    WritePrimitive(scene_.primitives[i], GeomSource{static_cast<int>(i), -1});
  }
  for (std::size_t k = 0; k < scene_.dynamic_objects.size(); ++k) {
    const DynamicObject& o = scene_.dynamic_objects[k];
    const Eigen::Isometry3d T = DynamicObjectPose(o, 0.0);
    body_ << "    <body name=\"dyn" << k << "\" mocap=\"true\" pos=\"" << Vec(T.translation()) << "\" quat=\""
          << Quat(T.linear()) << "\">\n";
    for (std::size_t i = 0; i < o.parts.size(); ++i) {
      WritePrimitive(o.parts[i], GeomSource{static_cast<int>(i), static_cast<int>(k)});
    }
    body_ << "    </body>\n";
  }
  const Eigen::AlignedBox3d box = BuildMesh(scene_).Bounds();
  const SceneLighting& l = scene_.lighting;
  std::ostringstream xml;
  xml << std::setprecision(12) << "<mujoco model=\"" << scene_.name << "\">\n"
      << "  <compiler angle=\"radian\" convexhull=\"false\"/>\n"
      << "  <default><geom contype=\"0\" conaffinity=\"0\"/></default>\n"
      << "  <statistic extent=\"" << box.diagonal().norm() << "\" center=\"" << Vec(box.center()) << "\"/>\n"
      << "  <visual>\n    <headlight ambient=\"" << Vec(Eigen::Vector3d::Constant(l.ambient)) << "\" diffuse=\""
      << Vec(Eigen::Vector3d::Constant(l.headlight)) << "\" specular=\"0.05 0.05 0.05\"/>\n  </visual>\n"
      << "  <asset>\n" << assets_.str() << "  </asset>\n"
      << "  <worldbody>\n" << body_.str() << "  </worldbody>\n</mujoco>\n";
  return xml.str();
}

/// Copies each generated texture image into the compiled model (mjr_makeContext uploads them later).
Status FillTextures(const Scene& scene, mjModel* m) {
  for (int id = 0; id < m->ntex; ++id) {
    const char* name = m->names + m->name_texadr[id];
    if (std::strncmp(name, "tex_", 4) != 0) continue;
    const TextureSpec* spec = FindTexture(scene.textures, name + 4);
    if (!spec) return Status::Error(std::string("mujoco scene: no texture spec for ") + name);
    const RgbImage image = RenderTexture(*spec);
    if (m->tex_width[id] != image.width || m->tex_height[id] != image.height) {
      return Status::Error(std::string("mujoco scene: texture size mismatch for ") + name);
    }
    std::memcpy(m->tex_rgb + m->tex_adr[id], image.rgb.data(), image.rgb.size());
  }
  return Status::Ok();
}

/// Compiles MJCF text from memory (MuJoCo 2.2.2 has no load-from-string: a virtual file system holds it).
Status CompileMjcf(const std::string& xml, mjModel** model) {
  auto vfs = std::make_unique<mjVFS>();  // ~2 MB: keep it off the stack
  mj_defaultVFS(vfs.get());
  const char* kName = "rotolidar_scene.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), kName, static_cast<int>(xml.size())) != 0) {
    return Status::Error("mujoco scene: cannot allocate the virtual file");
  }
  const int index = mj_findFileVFS(vfs.get(), kName);
  std::memcpy(vfs->filedata[index], xml.data(), xml.size());
  char error[1024] = "";
  *model = mj_loadXML(kName, vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  if (!*model) return Status::Error(std::string("mujoco scene: MJCF does not compile: ") + error);
  return Status::Ok();
}

}  // namespace

std::string SceneToMjcf(const Scene& scene, std::vector<GeomSource>* sources) {
  if (sources) sources->clear();
  return MjcfWriter(scene, sources).Write();
}

Status MujocoScene::Create(const Scene& scene, std::unique_ptr<MujocoScene>* out, Seconds t0) {
  ROTOLIDAR_CHECK(out != nullptr, "MujocoScene::Create needs an output");
  std::unique_ptr<MujocoScene> ms(new MujocoScene());
  ms->mjcf_ = SceneToMjcf(scene, &ms->sources_);
  if (Status s = CompileMjcf(ms->mjcf_, &ms->model_); !s) return s;
  if (ms->model_->ngeom != static_cast<int>(ms->sources_.size())) {
    return Status::Error("mujoco scene: compiled " + std::to_string(ms->model_->ngeom) + " geoms, generated " +
                         std::to_string(ms->sources_.size()));
  }
  if (Status s = FillTextures(scene, ms->model_); !s) return s;
  ms->data_ = mj_makeData(ms->model_);
  if (!ms->data_) return Status::Error("mujoco scene: mj_makeData failed");
  ms->objects_ = scene.dynamic_objects;
  ms->SetTime(t0);
  *out = std::move(ms);
  return Status::Ok();
}

MujocoScene::~MujocoScene() {
  if (data_) mj_deleteData(data_);
  if (model_) mj_deleteModel(model_);
}

void MujocoScene::SetTime(Seconds t) {
  for (std::size_t k = 0; k < objects_.size(); ++k) {
    const Eigen::Isometry3d T = DynamicObjectPose(objects_[k], t);
    const Eigen::Quaterniond q(T.linear());
    const int mocap = model_->body_mocapid[mj_name2id(model_, mjOBJ_BODY, ("dyn" + std::to_string(k)).c_str())];
    for (int i = 0; i < 3; ++i) data_->mocap_pos[3 * mocap + i] = T.translation()[i];
    data_->mocap_quat[4 * mocap + 0] = q.w();
    data_->mocap_quat[4 * mocap + 1] = q.x();
    data_->mocap_quat[4 * mocap + 2] = q.y();
    data_->mocap_quat[4 * mocap + 3] = q.z();
  }
  data_->time = t;
  mj_kinematics(model_, data_);
  mj_camlight(model_, data_);
}

double MujocoScene::Ray(const Eigen::Vector3d& origin_world, const Eigen::Vector3d& dir_world, int* geom_id) const {
  const Eigen::Vector3d dir = dir_world.normalized();
  const mjtNum pnt[3] = {origin_world.x(), origin_world.y(), origin_world.z()};
  const mjtNum vec[3] = {dir.x(), dir.y(), dir.z()};
  int geom = -1;
  const mjtNum distance = mj_ray(model_, data_, pnt, vec, nullptr, 1, -1, &geom);
  if (geom_id) *geom_id = geom;
  return distance;
}

}  // namespace rotolidar::sim
