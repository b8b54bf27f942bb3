#pragma once
// Internal to core/io/kitti*.cpp: strict text parsing and shortest round-trip number formatting for the KITTI
// files. Not part of the public API.
#include <string>
#include <vector>

#include "core/io/kitti.hpp"

namespace rotolidar::kitti_text {

std::string Where(const std::string& path, int line);  ///< "path:line: "
/// Whole-token, locale-independent parse; a leading '+' is accepted; NaN and inf are rejected.
bool ParseNumber(const std::string& token, double* value);
std::string FormatNumber(double value);  ///< shortest form that reads back to the identical double
Status ReadLines(const std::string& path, std::vector<std::string>* lines);
/// tokens[first..] must be exactly `count` finite numbers; errors name path:line, `what` and the field index.
Status ParseNumbers(const std::string& path, int line, const std::vector<std::string>& tokens, size_t first,
                    size_t count, const std::string& what, std::vector<double>* values);
Matrix34d ToMatrix34(const std::vector<double>& row_major_12);
/// M's 3x3 block must be a rotation within 1e-3; the pose keeps M exactly.
Status ToPose(const std::string& path, int line, const std::string& what, const Matrix34d& M, Pose3* pose);
std::string FormatRow(const Matrix34d& M);  ///< 12 numbers, row-major, space-separated
Status WriteText(const std::string& path, const std::string& text);
/// Drops trailing empty lines; any other empty line is an error; no content at all is an error.
Status ContentLines(const std::string& path, std::vector<std::string>* lines);

}  // namespace rotolidar::kitti_text
