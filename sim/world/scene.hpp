#pragma once
// The sim's world: a scene description (primitives with materials, annotated elements), its YAML loader
// (docs/scene_format.md) and the triangle mesh every consumer builds from (Embree for the LiDAR, later MuJoCo
// for physics and the camera), so that all of them see the same geometry.
//
// Frame: everything here is in the world frame (z up), metres. Angles in the YAML are degrees; in the structs
// radians.
#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/util/log.hpp"

namespace rotolidar::sim {

/// Surface properties at the LiDAR's 903 nm (and a texture name for the camera).
struct Material {
  std::string name;
  double albedo = 0.5;           ///< diffuse reflectivity at 903 nm, [0, 1]
  bool retroreflective = false;  ///< the VLP-16 reports 101..255 for these
  std::string texture;           ///< optional texture name for the camera ("" = plain colour)
};

enum class PrimitiveType { kBox, kQuad, kCylinder };

/// One solid or surface. Orientation R = Rz(yaw) * Ry(pitch) * Rx(roll) maps primitive axes to world axes.
struct Primitive {
  PrimitiveType type = PrimitiveType::kBox;
  std::string name;
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();  ///< box/quad/cylinder centre (cylinder: mid-height)
  Eigen::Vector3d rpy_rad = Eigen::Vector3d::Zero();   ///< roll, pitch, yaw
  Eigen::Vector3d size_m = Eigen::Vector3d::Ones();    ///< box: full extents x, y, z; quad: x, y (z unused)
  double radius_m = 0.0;   ///< cylinder only
  double height_m = 0.0;   ///< cylinder only, along its local z axis
  int segments = 24;       ///< cylinder only: facets around the axis (>= 3)
  bool inward = false;     ///< box only: emit the 6 faces facing inside (a room); else facing outside
  int material_id = 0;     ///< index into Scene::materials
  int floor_material_id = -1;    ///< box only: material of the -z face (-1 = material_id)
  int ceiling_material_id = -1;  ///< box only: material of the +z face (-1 = material_id)

  Eigen::Matrix3d Rotation() const;  ///< R_world_primitive
};

/// A named element for later stages (door, window, column): stored, not meshed.
struct AnnotatedElement {
  std::string name;
  std::string type;  ///< "door", "window" or "column"
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();
  double width_m = 0.0;
  double height_m = 0.0;
  double yaw_rad = 0.0;  ///< orientation of the element's plane about z (0: the plane's normal is +x)
};

struct Scene {
  std::string name;
  std::string source_path;  ///< file it was loaded from ("" when built in code)
  bool closed = false;      ///< true: the geometry encloses `bounds`, rays from inside always hit something
  Eigen::AlignedBox3d bounds;  ///< the region the rig may move in [m]
  std::vector<Material> materials;
  std::vector<Primitive> primitives;
  std::vector<AnnotatedElement> elements;

  /// Index of the material called `name`, or -1.
  int FindMaterial(const std::string& name) const;
  /// Checks sizes, material references and albedos; on failure false with the primitive/material named.
  bool Validate(std::string* error) const;
};

/// Triangle soup in the world frame. Triangles wind counter-clockwise seen from their front side, so the front
/// normal is (v1 - v0) x (v2 - v0). Every array indexed by triangle has triangles.size() entries.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices_m;
  std::vector<Eigen::Vector3i> triangles;  ///< vertex indices
  std::vector<int> material_ids;           ///< per triangle, index into `materials`
  std::vector<int> primitive_ids;          ///< per triangle, index into Scene::primitives
  std::vector<Material> materials;         ///< copied from the scene

  /// Appends a triangle (vertex indices must already exist).
  void AddTriangle(int a, int b, int c, int material_id, int primitive_id);
};

/// Loads a scene file. Never throws: YAML syntax errors, unknown keys, wrong types and invalid values come back
/// as a Status whose message reads "<path>:<line>: <what> (<key>)" (1-based line).
Status LoadScene(const std::string& path, Scene* scene);

/// Tessellates every primitive (deterministic: the same scene gives the same mesh, bit for bit).
/// The scene must be valid (Scene::Validate); primitives with bad material ids are a programmer error.
TriangleMesh BuildMesh(const Scene& scene);

/// Appends the 6 faces of a box (12 triangles). `inward` = faces point into the box (a room's walls).
/// face_materials: -x, +x, -y, +y, -z, +z.
void AppendBox(const Eigen::Vector3d& center_m, const Eigen::Matrix3d& R_world_box, const Eigen::Vector3d& size_m,
               bool inward, const std::array<int, 6>& face_materials, int primitive_id, TriangleMesh* mesh);

/// A room: the inner faces of a hollow axis-aligned box (floor/ceiling by material) — a convenience for tests.
Primitive MakeRoom(const std::string& name, const Eigen::Vector3d& center_m, const Eigen::Vector3d& size_m,
                   int material_id);

}  // namespace rotolidar::sim
