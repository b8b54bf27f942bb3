// Mesh files through PCL's readers, and the element truth file.
#include "sim/world/mesh_io.hpp"
#include "core/io/point_cloud_header.hpp"
#include "core/util/log.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <iomanip>

#include <pcl/PolygonMesh.h>
#include <pcl/conversions.h>
#include <pcl/io/obj_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

namespace rotolidar::sim {
namespace {

std::string LowerExtension(const std::string& path) {
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

double TriangleArea2(const MeshAsset& m, const Eigen::Vector3i& t) {
  const Eigen::Vector3d& a = m.vertices_m[t[0]];
  return (m.vertices_m[t[1]] - a).cross(m.vertices_m[t[2]] - a).norm();
}

}  // namespace

Status LoadMeshFile(const std::string& path, MeshAsset* mesh) {
  ROTOLIDAR_CHECK(mesh != nullptr, "LoadMeshFile needs an output");
  const std::string ext = LowerExtension(path);
  if (ext != "obj" && ext != "ply") return Status::Error(path + ": mesh files must be .obj or .ply");
  if (!std::ifstream(path)) return Status::Error(path + ": cannot open mesh file");
  if (ext == "ply") {
    if (Status st = CheckPointCloudHeader(path); !st.ok) return st;
  }
  pcl::PolygonMesh polygon_mesh;
  int rc = -1;
  try {  // PCL throws on some malformed files (std::length_error, pcl::IOException)
    rc = ext == "obj" ? pcl::io::loadOBJFile(path, polygon_mesh) : pcl::io::loadPLYFile(path, polygon_mesh);
  } catch (const std::exception& e) {
    return Status::Error(path + ": PCL could not read the mesh (" + e.what() + ")");
  }
  if (rc < 0) return Status::Error(path + ": PCL could not read the mesh (code " + std::to_string(rc) + ")");
  pcl::PointCloud<pcl::PointXYZ> cloud;
  pcl::fromPCLPointCloud2(polygon_mesh.cloud, cloud);
  MeshAsset out;
  out.file = mesh->file;
  out.path = path;
  out.vertices_m.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d v = cloud[i].getVector3fMap().cast<double>();
    if (!v.allFinite()) return Status::Error(path + ": vertex " + std::to_string(i) + " is not finite");
    out.vertices_m.push_back(v);
  }
  const int n = static_cast<int>(out.vertices_m.size());
  for (std::size_t f = 0; f < polygon_mesh.polygons.size(); ++f) {
    const auto& idx = polygon_mesh.polygons[f].vertices;  // pcl::Indices
    for (const auto i : idx) {
      if (i < 0 || static_cast<int64_t>(i) >= n) {
        return Status::Error(path + ": face " + std::to_string(f) + " indexes missing vertex " + std::to_string(i));
      }
    }
    for (std::size_t k = 1; k + 1 < idx.size(); ++k) {  // fan: keeps the polygon's winding
      const Eigen::Vector3i tri(static_cast<int>(idx[0]), static_cast<int>(idx[k]), static_cast<int>(idx[k + 1]));
      if (TriangleArea2(out, tri) > 1e-12) out.triangles.push_back(tri);
    }
  }
  if (out.triangles.empty()) return Status::Error(path + ": mesh has no triangles of non-zero area");
  *mesh = std::move(out);
  return Status::Ok();
}

Status WriteObjFile(const std::string& path, const MeshAsset& mesh) {
  std::ofstream file(path);
  if (!file) return Status::Error(path + ": cannot write");
  file << "# rotolidar mesh: " << mesh.vertices_m.size() << " vertices, " << mesh.triangles.size()
       << " triangles (metres, counter-clockwise = front)\n"
       << std::setprecision(9);
  for (const Eigen::Vector3d& v : mesh.vertices_m) file << "v " << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (const Eigen::Vector3i& t : mesh.triangles) {
    file << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
  }
  return file ? Status::Ok() : Status::Error(path + ": write failed");
}

Status WriteElementTruth(const Scene& scene, const std::string& path) {
  std::ofstream file(path);
  if (!file) return Status::Error(path + ": cannot write");
  file << "name,type,frame,x_m,y_m,z_m,qw,qx,qy,qz,yaw_rad,width_m,height_m,depth_m,open\n" << std::setprecision(17);
  for (const AnnotatedElement& e : scene.elements) {
    const Eigen::Isometry3d T = e.T_world_element();
    const Eigen::Quaterniond q(T.linear());
    const Eigen::Vector3d& t = T.translation();
    file << e.name << "," << e.type << ",world," << t.x() << "," << t.y() << "," << t.z() << "," << q.w() << ","
         << q.x() << "," << q.y() << "," << q.z() << "," << e.yaw_rad << "," << e.width_m << "," << e.height_m << ","
         << e.depth_m << "," << (e.open ? 1 : 0) << "\n";
  }
  return file ? Status::Ok() : Status::Error(path + ": write failed");
}

}  // namespace rotolidar::sim
