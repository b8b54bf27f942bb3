#pragma once
// The loop closer's database entry, shared by its two source files (not part of the public API).
#include <vector>

#include <Eigen/Core>

#include "core/graph/loop_closer.hpp"

namespace rotolidar::graph {

/// What the database keeps of a keyframe (bounded: thinned points only).
struct LoopCloser::Keyframe {
  Seconds t_s = 0.0;
  Pose3 T_world_odom = Pose3::Identity();
  Eigen::Matrix3d R_level_base = Eigen::Matrix3d::Identity();  ///< the descriptor's gravity-aligned frame
  std::vector<Eigen::Vector3d> cloud_base;  ///< cloud_voxel_m-thinned points (verification), base frame [m]
  std::vector<Eigen::Vector3f> map_base;    ///< map_voxel_m-thinned points (the rebuilt map), base frame [m]
  bool has_bow = false;                     ///< its image is in the bag-of-words database
};

}  // namespace rotolidar::graph
