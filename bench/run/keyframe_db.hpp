#pragma once
// The loop closer's keyframe database saved with a run (`rotolidar slam --save-keyframes`), so a later study or
// session can reuse it without re-running the odometry:
//   <dir>/keyframes.csv   one row per keyframe: t_s, id, T_world_odom, T_world_corrected (x y z [m], qx qy qz qw),
//                         R_level_base (qx qy qz qw: base -> the descriptor's gravity-aligned frame), num_points
//   <dir>/kf_NNNNNN.pcd   its thinned points, base frame [m] (PCD, float32: ~1e-6 m rounding at 40 m); none when
//                         num_points is 0
// The descriptor is not stored: ComputeLidarDescriptor recomputes it from the points in the levelled frame.
#include <string>
#include <vector>

#include "core/graph/loop_closer.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

/// Writes `keyframes` into `dir` (created when missing). Errors name the file.
Status WriteKeyframeDatabase(const std::string& dir, const std::vector<graph::KeyframeCloud>& keyframes);

/// Reads a database WriteKeyframeDatabase wrote. Errors name the file and line (a bad row, a non-unit quaternion,
/// ids out of order, a missing or unreadable point file, a point count that differs from num_points).
Status ReadKeyframeDatabase(const std::string& dir, std::vector<graph::KeyframeCloud>* keyframes);

}  // namespace rotolidar::bench
