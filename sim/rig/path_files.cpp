#include "sim/rig/path_files.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/util/text.hpp"

namespace rotolidar::sim {
namespace {

/// Parses the whole of `token` as a finite double.
bool ParseNumber(const std::string& token, double* value) {
  const std::string t = TrimSpace(token);
  if (t.empty()) return false;
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (end != t.c_str() + t.size() || !std::isfinite(v)) return false;
  *value = v;
  return true;
}

std::vector<std::string> Split(const std::string& line, char sep) {
  std::vector<std::string> fields;
  std::stringstream ss(line);
  std::string field;
  while (std::getline(ss, field, sep)) fields.push_back(field);
  if (!line.empty() && line.back() == sep) fields.emplace_back();
  return fields;
}

std::vector<std::string> SplitWhitespace(const std::string& line) {
  std::vector<std::string> fields;
  std::istringstream ss(line);
  std::string field;
  while (ss >> field) fields.push_back(field);
  return fields;
}

/// Reads the non-blank lines of a file (comments after '#' removed when `comments`), with 1-based numbers.
Status ReadLines(const std::string& path, bool comments, std::vector<std::pair<int, std::string>>* lines) {
  std::ifstream in(path);
  if (!in) return Status::Error(path + ": cannot open file");
  std::string raw;
  for (int number = 1; std::getline(in, raw); ++number) {
    if (comments) raw = raw.substr(0, raw.find('#'));
    const std::string line = TrimSpace(raw);
    if (!line.empty()) lines->emplace_back(number, line);
  }
  return Status::Ok();
}

}  // namespace

Status LoadCarWaypointsCsv(const std::string& path, std::vector<CarWaypoint>* out) {
  std::vector<std::pair<int, std::string>> lines;
  if (Status s = ReadLines(path, true, &lines); !s) return s;
  static const char* kFields[] = {"x_m", "y_m", "speed_mps"};
  std::vector<CarWaypoint> points;
  for (size_t i = 0; i < lines.size(); ++i) {
    const auto& [number, line] = lines[i];
    const std::vector<std::string> fields = Split(line, ',');
    if (i == 0 && TrimSpace(fields[0]) == "x_m") continue;  // header
    if (fields.size() != 2 && fields.size() != 3)
      return Status::Error(FileLinePrefix(path, number) +
                           "expected 2 or 3 comma-separated fields (x_m,y_m[,speed_mps]), got " +
                           std::to_string(fields.size()));
    double v[3] = {0, 0, 0};
    for (size_t f = 0; f < fields.size(); ++f)
      if (!ParseNumber(fields[f], &v[f]))
        return Status::Error(FileLinePrefix(path, number) + "field '" + kFields[f] + "': cannot read number '" +
                             TrimSpace(fields[f]) + "'");
    if (fields.size() == 3 && v[2] <= 0)
      return Status::Error(FileLinePrefix(path, number) + "field 'speed_mps' must be > 0, got " +
                           TrimSpace(fields[2]));
    points.push_back({v[0], v[1], v[2], number});
  }
  if (points.size() < 2)
    return Status::Error(path + ": need at least 2 waypoints, got " + std::to_string(points.size()));
  *out = std::move(points);
  return Status::Ok();
}

Status LoadKittiPoses(const std::string& path, std::vector<Pose3>* out) {
  std::vector<std::pair<int, std::string>> lines;
  if (Status s = ReadLines(path, false, &lines); !s) return s;
  std::vector<Pose3> poses;
  poses.reserve(lines.size());
  for (const auto& [number, line] : lines) {
    const std::vector<std::string> fields = SplitWhitespace(line);
    if (fields.size() != 12)
      return Status::Error(FileLinePrefix(path, number) + "expected 12 numbers (row-major 3x4 [R|t]), got " +
                           std::to_string(fields.size()));
    Eigen::Matrix<double, 3, 4> m;
    for (int k = 0; k < 12; ++k)
      if (!ParseNumber(fields[size_t(k)], &m(k / 4, k % 4)))
        return Status::Error(FileLinePrefix(path, number) + "field " + std::to_string(k + 1) + " (row " +
                             std::to_string(k / 4) + ", col " + std::to_string(k % 4) + "): cannot read number '" +
                             fields[size_t(k)] + "'");
    const Eigen::Matrix3d R = m.leftCols<3>();
    const double orthonormality = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
    if (orthonormality > 1e-3 || R.determinant() < 0)
      return Status::Error(FileLinePrefix(path, number) + "rotation is not orthonormal (|R^T R - I| = " +
                           std::to_string(orthonormality) + ")");
    Pose3 T = Pose3::Identity();
    T.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
    T.translation() = m.col(3);
    poses.push_back(T);
  }
  if (poses.size() < 2) return Status::Error(path + ": need at least 2 poses, got " + std::to_string(poses.size()));
  *out = std::move(poses);
  return Status::Ok();
}

Status LoadKittiTimes(const std::string& path, std::vector<double>* out) {
  std::vector<std::pair<int, std::string>> lines;
  if (Status s = ReadLines(path, false, &lines); !s) return s;
  std::vector<double> times;
  times.reserve(lines.size());
  for (const auto& [number, line] : lines) {
    double t = 0;
    if (!ParseNumber(line, &t))
      return Status::Error(FileLinePrefix(path, number) + "field 't_s': cannot read number '" + line + "'");
    if (!times.empty() && !(t > times.back()))
      return Status::Error(FileLinePrefix(path, number) + "field 't_s': times must increase strictly (" + line +
                           " after " + std::to_string(times.back()) + ")");
    times.push_back(t);
  }
  if (times.size() < 2) return Status::Error(path + ": need at least 2 times, got " + std::to_string(times.size()));
  *out = std::move(times);
  return Status::Ok();
}

}  // namespace rotolidar::sim
