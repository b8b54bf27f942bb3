#pragma once
// Point cloud files through PCL: PLY (binary) and PCD (binary), xyz in metres.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/util/status.hpp"

namespace rotolidar {

Status SavePointCloud(const std::string& path, const std::vector<Eigen::Vector3d>& points);  ///< .ply or .pcd
Status LoadPointCloud(const std::string& path, std::vector<Eigen::Vector3d>* points);        ///< .ply or .pcd

}  // namespace rotolidar
