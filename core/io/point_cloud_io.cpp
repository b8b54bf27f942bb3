#include "core/io/point_cloud_io.hpp"

#include "core/io/point_cloud_header.hpp"

#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

namespace rotolidar {
namespace {

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

Status SavePointCloud(const std::string& path, const std::vector<Eigen::Vector3d>& points) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.reserve(points.size());
  for (const auto& p : points) cloud.push_back(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())));
  if (cloud.empty()) return Status::Error(path + ": refusing to write an empty point cloud");
  int rc = -1;
  if (EndsWith(path, ".ply"))  // binary, no "camera" element: a map has no viewpoint, and readers warn on it
    rc = pcl::PLYWriter().write(path, cloud, /*binary=*/true, /*use_camera=*/false);
  else if (EndsWith(path, ".pcd"))
    rc = pcl::io::savePCDFileBinary(path, cloud);
  else
    return Status::Error(path + ": unknown point cloud extension (use .ply or .pcd)");
  return rc == 0 ? Status::Ok() : Status::Error(path + ": PCL could not write the file");
}

Status LoadPointCloud(const std::string& path, std::vector<Eigen::Vector3d>* points) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  int rc = -1;
  if (!EndsWith(path, ".ply") && !EndsWith(path, ".pcd"))
    return Status::Error(path + ": unknown point cloud extension (use .ply or .pcd)");
  if (Status st = CheckPointCloudHeader(path); !st.ok) return st;
  try {  // PCL throws on some inputs the header check lets through (std::length_error, pcl::IOException)
    rc = EndsWith(path, ".ply") ? pcl::io::loadPLYFile(path, cloud) : pcl::io::loadPCDFile(path, cloud);
  } catch (const std::exception& e) {
    return Status::Error(path + ": PCL could not read the file (" + e.what() + ")");
  }
  if (rc != 0) return Status::Error(path + ": PCL could not read the file");
  points->clear();
  points->reserve(cloud.size());
  for (const auto& p : cloud.points) points->emplace_back(p.x, p.y, p.z);
  return Status::Ok();
}

}  // namespace rotolidar
