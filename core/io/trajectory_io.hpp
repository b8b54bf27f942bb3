#pragma once
// Trajectory files in the three formats evo reads (github.com/MichaelGrupp/evo, evo/tools/file_interface.py):
//
//  - TUM:   one pose a line, `t x y z qx qy qz qw` (seconds, metres, unit quaternion Hamilton x y z w),
//           separated by whitespace; lines that are empty or start with '#' are skipped.
//  - KITTI: one pose a line, 12 floats = the row-major 3x4 matrix [R | t] of T_ref_body. The file has no times:
//           they come from an optional times file (one time [s] a line, same count as poses), else the pose
//           index (0, 1, 2, ...). The rotation block is kept as written (like evo, no re-orthonormalisation)
//           but is rejected if it is clearly not a rotation (|R^T R - I| > 1e-3 in any entry).
//  - EuRoC: ground-truth CSV `timestamp [ns], p_x, p_y, p_z, q_w, q_x, q_y, q_z, ...` (further columns such as
//           velocity and biases are ignored); lines starting with '#' are skipped. Times become seconds.
//
// A file without any pose is an error. Times must be non-decreasing. Equal consecutive times are kept as in the file (real evo test data, e.g. TUM
// fr2/desk ground truth, contains exact duplicates and evo keeps them); a decreasing time is an error.
// Errors name `file:line`, the field and the offending text. Nothing is thrown; no partial output on failure.
// Writers print every double with max_digits10 significant digits, so a write -> read round trip reproduces
// times and translations bit-exactly and rotations to ~1e-15 (quaternion <-> matrix conversion).
#include <string>

#include "core/types/trajectory.hpp"
#include "core/util/status.hpp"

namespace rotolidar {

enum class TrajectoryFormat { kTum, kKitti, kEuroc };

/// "tum", "kitti", "euroc" -> format; false (out untouched) for any other name.
bool ParseTrajectoryFormat(const std::string& name, TrajectoryFormat* out);
const char* TrajectoryFormatName(TrajectoryFormat format);

/// Reads `path` into `out` (replaced on success, untouched on failure). `times_path` is used by KITTI only
/// (empty: times are the pose indices); giving one for another format is an error.
Status ReadTrajectory(const std::string& path, TrajectoryFormat format, Trajectory* out,
                      const std::string& times_path = "");

/// Writes `traj` to `path` (overwritten). KITTI stores no times: write them with WriteKittiTimes if needed.
/// EuRoC writes the 8 pose columns with times rounded to integer nanoseconds.
Status WriteTrajectory(const std::string& path, TrajectoryFormat format, const Trajectory& traj);

/// Writes the times of `traj` one per line (the KITTI times.txt companion file), full precision.
Status WriteKittiTimes(const std::string& path, const Trajectory& traj);

}  // namespace rotolidar
