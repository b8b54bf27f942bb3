#pragma once
// Loaders for the files carrier paths are made from (sim/rig/carrier_paths):
//   - car waypoint CSV: one point a line, "x_m,y_m" or "x_m,y_m,speed_mps" (world frame, z up); '#' starts a
//     comment; blank lines are skipped; a first line naming the columns (x_m,y_m[,speed_mps]) is allowed.
//   - KITTI odometry poses: 12 floats a line, the row-major 3x4 [R|t] of T_cam0start_cam0k (cam0: x right,
//     y down, z forward; metres), one line per frame.
//   - KITTI times: one float a line [s], one line per frame (times.txt).
// Every loader returns a Status whose message names file:line and the field; on failure *out is untouched.
#include <string>
#include <vector>

#include "core/types/geometry.hpp"
#include "core/util/status.hpp"

namespace rotolidar::sim {

struct CarWaypoint {
  double x_m = 0.0, y_m = 0.0;  ///< world frame [m]
  double speed_mps = 0.0;       ///< target speed [m/s]; 0 = not given (the path's cruise speed applies)
  int line = 0;                 ///< 1-based line in the file (for messages)
};

/// Reads a car waypoint CSV. Errors: unreadable file, a row without 2 or 3 numeric fields, non-finite values,
/// speed_mps <= 0 where given, fewer than 2 points.
Status LoadCarWaypointsCsv(const std::string& path, std::vector<CarWaypoint>* out);

/// Reads a KITTI poses file into T_cam0start_cam0k. Errors: unreadable file, a line without exactly 12
/// numbers, a rotation that is not orthonormal within 1e-3, fewer than 2 poses.
Status LoadKittiPoses(const std::string& path, std::vector<Pose3>* out);

/// Reads a KITTI times file. Errors: unreadable file, a line that is not one number, times not strictly
/// increasing, fewer than 2 times.
Status LoadKittiTimes(const std::string& path, std::vector<double>* out);

}  // namespace rotolidar::sim
