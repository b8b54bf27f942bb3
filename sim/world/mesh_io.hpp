#pragma once
// File I/O of the world: triangle mesh files (OBJ/PLY, read with PCL) and the truth file of a scene's annotated
// elements (what a tape measure would give: name, type, frame, width, height).
#include <string>

#include "core/util/status.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim {

/// Reads an OBJ or PLY file (chosen by the extension, case-insensitive) with PCL (pcl::io::loadOBJFile /
/// loadPLYFile into a pcl::PolygonMesh). Polygons with more than 3 corners are fan-triangulated (keeping their
/// winding); triangles of zero area are dropped (they have no surface). Units: metres, the file's own frame.
/// Fails, naming the file (and the face where it applies), when the file cannot be read, a face indexes a
/// missing vertex, a vertex is not finite, or no triangle is left. Sets mesh->path; leaves mesh->file alone.
Status LoadMeshFile(const std::string& path, MeshAsset* mesh);

/// Writes `mesh` as a Wavefront OBJ ("v x y z", "f a b c" 1-based, 9 significant digits). For generators and
/// tests; the result reads back with LoadMeshFile.
Status WriteObjFile(const std::string& path, const MeshAsset& mesh);

/// Writes the annotated elements as CSV, one row per element:
///   name,type,frame,x_m,y_m,z_m,qw,qx,qy,qz,yaw_rad,width_m,height_m,depth_m,open
/// where frame is the parent frame ("world") and (x, y, z, q) is T_world_element (AnnotatedElement's frame).
/// Numbers carry 17 significant digits (they round-trip exactly). Fails naming the path when it cannot write.
Status WriteElementTruth(const Scene& scene, const std::string& path);

}  // namespace rotolidar::sim
