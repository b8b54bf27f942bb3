#pragma once
// The sim's world: a scene description (primitives, meshes, materials, textures, lighting, dynamic objects,
// annotated elements with true dimensions, default carrier paths), its YAML loader (docs/scene_format.md) and
// the triangle mesh every consumer builds from (Embree for the LiDAR, MuJoCo for physics and the camera), so
// that all of them see the same geometry.
//
// Frame: everything here is in the world frame (z up), metres, unless a comment names the body frame of a
// dynamic object. Angles in the YAML are degrees; in the structs radians.
#include <array>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/types/time.hpp"
#include "core/util/status.hpp"
#include "sim/rig/waypoint.hpp"
#include "sim/world/texture.hpp"

namespace rotolidar::sim {

/// Surface properties: the LiDAR's reflectivity at 903 nm and the camera's colour and texture.
struct Material {
  std::string name;
  double albedo = 0.5;           ///< LiDAR reflectivity: diffuse reflectance at 903 nm, [0, 1]
  bool retroreflective = false;  ///< the VLP-16 reports 101..255 for these
  std::string texture;           ///< texture name for the camera ("" = plain colour); see texture.hpp
  /// Visible albedo (camera colour), RGB in [0, 1]; multiplies the texture. The loader defaults it to white
  /// for textured materials (the texture carries the colour) and to 0.7 grey otherwise.
  Eigen::Vector3d color_rgb = Eigen::Vector3d(0.7, 0.7, 0.7);
  /// LiDAR only: fraction of the power a surface of this material passes on (glass, porous foliage), [0, 1),
  /// with albedo + transmittance + specular <= 1. The sim adds every material with transmittance > 0 to the
  /// caster's lidar.material_transmittance unless the run's config lists that material itself (sim/sim_runner.cpp).
  double transmittance = 0.0;
  /// Fraction of the LiDAR beam reflected specularly (a mirror: ~0.9; albedo + transmittance + specular <= 1);
  /// the VLP-16 twin follows it when its specular_reflections switch is on (docs/lidar_model.md).
  double specular = 0.0;
};

enum class PrimitiveType { kBox, kQuad, kCylinder, kMesh };
/// The types' words in scene files: "box", "quad" (or "plane"), "cylinder", "mesh" (core/io/yaml_fields.hpp finds
/// it by argument-dependent lookup).
const std::vector<std::pair<const char*, PrimitiveType>>& EnumWords(PrimitiveType*);

/// One solid or surface. Orientation R = Rz(yaw) * Ry(pitch) * Rx(roll) maps primitive axes to world axes.
struct Primitive {
  PrimitiveType type = PrimitiveType::kBox;
  std::string name;
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();  ///< box/quad/cylinder centre (cylinder: mid-height); mesh origin
  Eigen::Vector3d rpy_rad = Eigen::Vector3d::Zero();   ///< roll, pitch, yaw
  Eigen::Vector3d size_m = Eigen::Vector3d::Ones();    ///< box: full extents x, y, z; quad: x, y (z unused)
  double radius_m = 0.0;   ///< cylinder only
  double height_m = 0.0;   ///< cylinder only, along its local z axis
  int segments = 24;       ///< cylinder only: facets around the axis (>= 3)
  bool inward = false;     ///< box only: emit the 6 faces facing inside (a room); else facing outside
  int material_id = 0;     ///< index into Scene::materials
  int floor_material_id = -1;    ///< box only: material of the -z face (-1 = material_id)
  int ceiling_material_id = -1;  ///< box only: material of the +z face (-1 = material_id)
  int mesh_id = -1;        ///< mesh only: index into Scene::meshes
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();  ///< mesh only: per-axis scale of the file's vertices
  /// Pictures only: left out of top views (roofs, ceilings). Inward boxes always leave out their +z face there.
  bool hide_in_top_view = false;

  Eigen::Matrix3d Rotation() const;  ///< R_world_primitive
};

/// Triangles read from a mesh file (OBJ/PLY, sim/world/mesh_io.hpp), in the file's own frame and units (m).
struct MeshAsset {
  std::string file;  ///< as written in the scene (relative to the scene file's folder)
  std::string path;  ///< resolved path it was read from
  std::vector<Eigen::Vector3d> vertices_m;
  std::vector<Eigen::Vector3i> triangles;  ///< counter-clockwise seen from the front
};

/// A named structural element with true dimensions, as a tape measure would give them (the scene's truth).
/// Its frame E: origin at the element's centre; x = the element's normal (through a door or window, or any
/// horizontal axis of a column), z = world up, y = z cross x (along the width).
struct AnnotatedElement {
  std::string name;
  std::string type;  ///< "door", "window" or "column"
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();  ///< centre of the opening / column [world]
  double width_m = 0.0;   ///< along E's y: opening width, or column width (diameter when round)
  double height_m = 0.0;  ///< along z
  double depth_m = 0.0;   ///< along E's x: wall thickness at the opening, or column depth (0 = not stated)
  double yaw_rad = 0.0;   ///< orientation of E about world z (0: E's x = world x)
  bool open = false;      ///< door/window: an empty opening (rays pass); false: a leaf or pane fills it
  std::string primitive;  ///< optional: the primitive that realises it (a column's cylinder or box)

  Eigen::Isometry3d T_world_element() const;
};

/// A person or car that moves along a polyline at constant horizontal speed. Its body frame B: origin on the
/// ground below its centre, x forward (along the path), z up (kept upright on slopes). Pose: scene_dynamic.hpp.
struct DynamicObject {
  std::string name;
  std::string kind;                      ///< "person" or "car"
  std::vector<Primitive> parts;          ///< in the body frame B (kind's default body unless the file gives one)
  /// World waypoints (>= 2): xy and the height of the ground the body stands on there (z, interpolated).
  std::vector<Eigen::Vector3d> path_m;
  double speed_mps = 1.0;                ///< along the path, horizontal (> 0)
  double start_offset_m = 0.0;           ///< horizontal arc length along the path at t = 0
  bool loop = true;                      ///< true: the path closes (last -> first); false: back and forth
};

/// Scene-level light for the camera (the LiDAR ignores it).
struct SceneLight {
  Eigen::Vector3d position_m = Eigen::Vector3d(0, 0, 10);
  Eigen::Vector3d direction = Eigen::Vector3d(0, 0, -1);  ///< unit, where it shines
  bool directional = false;  ///< true: a sun-like light (position irrelevant); false: a spot light
  double intensity = 0.5;    ///< diffuse, [0, 1]
  bool cast_shadow = false;
};

struct SceneLighting {
  double ambient = 0.35;    ///< uniform ambient light, [0, 1] (a dark underground garage: ~0.05)
  double headlight = 0.35;  ///< light carried by the viewing camera, [0, 1]
  Eigen::Vector3d sky_rgb = Eigen::Vector3d(0.55, 0.70, 0.90);  ///< background colour (outdoors: the sky)
  std::vector<SceneLight> lights;
};

/// A viewpoint for pictures (`rotolidar scene show`): eye and target in the world, vertical field of view.
struct SceneView {
  bool set = false;  ///< false: the picture code picks a view from the bounds
  Eigen::Vector3d eye_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d target_m = Eigen::Vector3d::Zero();
  double fov_deg = 60.0;
};

struct Scene {
  std::string name;
  std::string description;
  std::string source_path;  ///< file it was loaded from ("" when built in code)
  bool closed = false;      ///< true: the geometry encloses `bounds`, rays from inside always hit something
  Eigen::AlignedBox3d bounds;  ///< the region the rig may move in [m]
  std::vector<Material> materials;
  std::vector<TextureSpec> textures;  ///< defined by the file; lookups fall back to BuiltinTextures()
  std::vector<MeshAsset> meshes;
  std::vector<Primitive> primitives;  ///< the static world
  std::vector<AnnotatedElement> elements;
  std::vector<DynamicObject> dynamic_objects;
  /// Default motion paths per carrier ("handheld", "wheeled", "car"), world xy; consumed by sim/rig's carriers.
  std::map<std::string, std::vector<Waypoint2d>> default_paths;
  std::vector<std::string> path_order;  ///< keys of default_paths in the file's order (the first is a default)
  SceneLighting lighting;
  SceneView view;

  /// Index of the material called `name`, or -1.
  int FindMaterial(const std::string& name) const;
  /// Checks sizes, material/mesh/texture references, albedos, elements, objects and paths; on failure false
  /// with the primitive/material/element named.
  bool Validate(std::string* error) const;
};

/// Triangle soup in the world frame. Triangles wind counter-clockwise seen from their front side, so the front
/// normal is (v1 - v0) x (v2 - v0). Every array indexed by triangle has triangles.size() entries.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices_m;
  std::vector<Eigen::Vector3i> triangles;  ///< vertex indices
  std::vector<int> material_ids;           ///< per triangle, index into `materials`
  std::vector<int> primitive_ids;          ///< per triangle, index into Scene::primitives (or an object's parts)
  std::vector<Material> materials;         ///< copied from the scene

  /// Appends a triangle (vertex indices must already exist).
  void AddTriangle(int a, int b, int c, int material_id, int primitive_id);
  /// Axis-aligned bounds of the vertices (empty box when there are none).
  Eigen::AlignedBox3d Bounds() const;
};

/// Checks one primitive against the scene's materials and meshes (sizes, references, orientation); on failure
/// false with the primitive named. Part of Scene::Validate.
bool ValidatePrimitive(const Primitive& primitive, const Scene& scene, std::string* error);

/// Loads a scene file. Never throws: YAML syntax errors, unknown keys, wrong types, unreadable mesh files and
/// invalid values come back as a Status whose message reads "<path>:<line>: <what> (<key>)" (1-based line).
/// A file with `extends: BASE` starts from the base scene (BASE.yaml or BASE, relative to the file's folder,
/// loaded the same way) and adds to it (docs/scene_format.md, 'Extending a scene'); a missing base, an error in
/// it and a cycle of extends come back naming the file and line of the `extends` key.
Status LoadScene(const std::string& path, Scene* scene);

/// Tessellates every static primitive (deterministic: the same scene gives the same mesh, bit for bit).
/// Dynamic objects are not included (EmbreeScene instances them; BuildMeshAt poses them).
/// The scene must be valid (Scene::Validate); primitives with bad material ids are a programmer error.
TriangleMesh BuildMesh(const Scene& scene);

/// Static mesh plus every dynamic object posed at time t (pictures, tests). primitive_ids of object triangles
/// are -1 - (object index).
TriangleMesh BuildMeshAt(const Scene& scene, Seconds t);

/// Tessellates a list of primitives into `mesh` (primitive_ids = index in `primitives`), in the frame the
/// primitives are expressed in; `meshes` resolves kMesh primitives.
void AppendPrimitives(const std::vector<Primitive>& primitives, const std::vector<MeshAsset>& meshes,
                      TriangleMesh* mesh);

/// Appends the 6 faces of a box (12 triangles). `inward` = faces point into the box (a room's walls).
/// face_materials: -x, +x, -y, +y, -z, +z.
void AppendBox(const Eigen::Vector3d& center_m, const Eigen::Matrix3d& R_world_box, const Eigen::Vector3d& size_m,
               bool inward, const std::array<int, 6>& face_materials, int primitive_id, TriangleMesh* mesh);

/// A room: the inner faces of a hollow axis-aligned box (floor/ceiling by material) — a convenience for tests.
Primitive MakeRoom(const std::string& name, const Eigen::Vector3d& center_m, const Eigen::Vector3d& size_m,
                   int material_id);

}  // namespace rotolidar::sim
