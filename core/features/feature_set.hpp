#pragma once
// The seed's LiDAR features of one scan: the interface between feature extraction (core/features) and
// scan-to-map registration (core/registration). Owned by value; PCL clouds so kd-trees and filters apply directly.
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "core/types/time.hpp"

namespace rotolidar {

/// Feature points of one deskewed scan, all in the base frame at the scan's start time t_s [m].
/// `intensity` carries the point's curvature (LOAM's c, seed Eq. 3) so consumers can weight or debug.
struct FeatureSet {
  Seconds t_s = 0.0;                           ///< scan start: the frame the points are expressed in
  pcl::PointCloud<pcl::PointXYZI> edge;        ///< sharpest points: per sector at most N_edge (scan side)
  pcl::PointCloud<pcl::PointXYZI> planar;      ///< flattest points: per sector at most N_planar (scan side)
  pcl::PointCloud<pcl::PointXYZI> less_sharp;  ///< denser edge set for the map side (LOAM's "less sharp")
  pcl::PointCloud<pcl::PointXYZI> less_flat;   ///< denser planar set for the map side (voxel-downsampled)
};

}  // namespace rotolidar
