#include "core/io/trajectory_io.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <vector>

#include "core/util/text.hpp"

namespace rotolidar {
namespace {

constexpr int kDigits = std::numeric_limits<double>::max_digits10;
const char* const kTumFields[] = {"t", "x", "y", "z", "qx", "qy", "qz", "qw"};
const char* const kEurocFields[] = {"timestamp_ns", "p_x", "p_y", "p_z", "q_w", "q_x", "q_y", "q_z"};

Status FieldError(const std::string& path, int line, const std::string& field, const std::string& token,
                  const std::string& what) {
  return Status::Error(FileLinePrefix(path, line) + "field '" + field + "' = '" + token + "': " + what);
}

/// Whitespace-separated tokens, or comma-separated (each trimmed) when `comma` is set.
std::vector<std::string> Split(const std::string& line, bool comma) {
  std::vector<std::string> out;
  if (comma) {
    std::stringstream ss(line);
    std::string tok;
    while (std::getline(ss, tok, ',')) out.push_back(TrimSpace(tok));
  } else {
    std::istringstream ss(line);
    std::string tok;
    while (ss >> tok) out.push_back(tok);
  }
  return out;
}

/// Locale-independent, whole-token double parse; accepts a leading '+'. Rejects NaN / inf.
bool ParseDouble(const std::string& tok, double* v) {
  const char* b = tok.data();
  const char* e = b + tok.size();
  if (b != e && *b == '+') ++b;
  const auto r = std::from_chars(b, e, *v);
  return r.ec == std::errc() && r.ptr == e && b != e && std::isfinite(*v);
}

bool ParseInt64(const std::string& tok, int64_t* v) {
  const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), *v);
  return r.ec == std::errc() && r.ptr == tok.data() + tok.size() && !tok.empty();
}

/// Parses fields [0, n) of `toks` as doubles into `vals`, naming `names[i]` on failure.
Status ParseDoubles(const std::vector<std::string>& toks, size_t first, size_t n, const char* const* names,
                    const std::string& path, int line, double* vals) {
  for (size_t i = first; i < n; ++i) {
    if (!ParseDouble(toks[i], &vals[i])) return FieldError(path, line, names[i], toks[i], "not a finite number");
  }
  return Status::Ok();
}

/// Reads the data lines of a text file: skips empty lines and lines whose first non-blank char is '#'.
Status ForEachDataLine(const std::string& path, std::vector<std::pair<int, std::string>>* lines) {
  std::ifstream in(path);
  if (!in) return Status::Error(path + ": cannot open for reading");
  std::string text;
  int line_no = 0;
  while (std::getline(in, text)) {
    ++line_no;
    const std::string t = TrimSpace(text);
    if (t.empty() || t[0] == '#') continue;
    lines->emplace_back(line_no, t);
  }
  if (in.bad()) return Status::Error(path + ": read error after line " + std::to_string(line_no));
  return Status::Ok();
}

Status MakeQuaternionPose(const Eigen::Vector3d& t, const Eigen::Quaterniond& q, const std::string& path,
                          int line, Pose3* T) {
  const double n = q.norm();
  if (!(n > 1e-9)) {
    return Status::Error(FileLinePrefix(path, line) + "field 'quaternion': norm " + std::to_string(n) + " is zero");
  }
  *T = MakePose(t, q);
  return Status::Ok();
}

Status ParseTumLine(const std::string& path, int line, const std::string& text, StampedPose* sp) {
  const auto toks = Split(text, false);
  if (toks.size() != 8) {
    return Status::Error(FileLinePrefix(path, line) + "expected 8 fields 't x y z qx qy qz qw', got " +
                         std::to_string(toks.size()));
  }
  double v[8];
  if (Status s = ParseDoubles(toks, 0, 8, kTumFields, path, line, v); !s) return s;
  sp->t_s = v[0];
  return MakeQuaternionPose({v[1], v[2], v[3]}, Eigen::Quaterniond(v[7], v[4], v[5], v[6]), path, line,
                            &sp->T_ref_body);
}

Status ParseKittiLine(const std::string& path, int line, const std::string& text, StampedPose* sp) {
  static const char* const kNames[] = {"r00", "r01", "r02", "tx", "r10", "r11",
                                       "r12", "ty",  "r20", "r21", "r22", "tz"};
  const auto toks = Split(text, false);
  if (toks.size() != 12) {
    return Status::Error(FileLinePrefix(path, line) + "expected 12 fields (row-major 3x4 [R|t]), got " +
                         std::to_string(toks.size()));
  }
  double v[12];
  if (Status s = ParseDoubles(toks, 0, 12, kNames, path, line, v); !s) return s;
  Pose3 T = Pose3::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) T.matrix()(r, c) = v[4 * r + c];
  }
  const double err = (T.linear().transpose() * T.linear() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(err <= 1e-3) || T.linear().determinant() <= 0.0) {
    return Status::Error(FileLinePrefix(path, line) + "fields 'r00'..'r22': not a rotation (|R^T R - I| = " +
                         std::to_string(err) + ")");
  }
  sp->T_ref_body = T;
  return Status::Ok();
}

Status ParseEurocLine(const std::string& path, int line, const std::string& text, StampedPose* sp) {
  const auto toks = Split(text, true);
  if (toks.size() < 8) {
    return Status::Error(FileLinePrefix(path, line) + "expected at least 8 comma-separated fields "
                         "'timestamp_ns, p_x, p_y, p_z, q_w, q_x, q_y, q_z', got " + std::to_string(toks.size()));
  }
  int64_t ns = 0;
  if (!ParseInt64(toks[0], &ns)) return FieldError(path, line, kEurocFields[0], toks[0], "not an integer");
  double v[8];
  if (Status s = ParseDoubles(toks, 1, 8, kEurocFields, path, line, v); !s) return s;
  // Split seconds and nanoseconds so the integer part stays exact.
  sp->t_s = static_cast<double>(ns / 1000000000) + static_cast<double>(ns % 1000000000) * 1e-9;
  return MakeQuaternionPose({v[1], v[2], v[3]}, Eigen::Quaterniond(v[4], v[5], v[6], v[7]), path, line,
                            &sp->T_ref_body);
}

Status CheckOrder(const std::string& path, const std::vector<std::pair<int, std::string>>& lines,
                  const Trajectory& traj) {
  for (size_t i = 1; i < traj.size(); ++i) {
    if (traj[i].t_s < traj[i - 1].t_s) {
      return Status::Error(FileLinePrefix(path, lines[i].first) + "field 't': time goes backwards (" +
                           std::to_string(traj[i].t_s) + " after " + std::to_string(traj[i - 1].t_s) + ")");
    }
  }
  return Status::Ok();
}

/// KITTI times: one double per data line, count must match.
Status ReadTimes(const std::string& path, Trajectory* traj) {
  std::vector<std::pair<int, std::string>> lines;
  if (Status s = ForEachDataLine(path, &lines); !s) return s;
  if (lines.size() != traj->size()) {
    return Status::Error(path + ": has " + std::to_string(lines.size()) + " times but the pose file has " +
                         std::to_string(traj->size()) + " poses");
  }
  for (size_t i = 0; i < lines.size(); ++i) {
    const auto toks = Split(lines[i].second, false);
    if (toks.size() != 1 || !ParseDouble(toks[0], &(*traj)[i].t_s)) {
      return FieldError(path, lines[i].first, "t", lines[i].second, "expected one finite number");
    }
  }
  return CheckOrder(path, lines, *traj);
}

void WriteTum(std::ostream& os, const Trajectory& traj) {
  os << "# t x y z qx qy qz qw\n";
  for (const auto& sp : traj) {
    const Eigen::Quaterniond q(sp.T_ref_body.linear());
    const Eigen::Vector3d& p = sp.T_ref_body.translation();
    os << sp.t_s << ' ' << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << q.x() << ' ' << q.y() << ' '
       << q.z() << ' ' << q.w() << '\n';
  }
}

void WriteKitti(std::ostream& os, const Trajectory& traj) {
  for (const auto& sp : traj) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) os << (r + c == 0 ? "" : " ") << sp.T_ref_body.matrix()(r, c);
    }
    os << '\n';
  }
}

void WriteEuroc(std::ostream& os, const Trajectory& traj) {
  os << "#timestamp [ns],p_x [m],p_y [m],p_z [m],q_w [],q_x [],q_y [],q_z []\n";
  for (const auto& sp : traj) {
    const double sec = std::floor(sp.t_s);
    const int64_t ns = static_cast<int64_t>(sec) * 1000000000 + std::llround((sp.t_s - sec) * 1e9);
    const Eigen::Quaterniond q(sp.T_ref_body.linear());
    const Eigen::Vector3d& p = sp.T_ref_body.translation();
    os << ns << ',' << p.x() << ',' << p.y() << ',' << p.z() << ',' << q.w() << ',' << q.x() << ',' << q.y()
       << ',' << q.z() << '\n';
  }
}

}  // namespace

bool ParseTrajectoryFormat(const std::string& name, TrajectoryFormat* out) {
  if (name == "tum") *out = TrajectoryFormat::kTum;
  else if (name == "kitti") *out = TrajectoryFormat::kKitti;
  else if (name == "euroc") *out = TrajectoryFormat::kEuroc;
  else return false;
  return true;
}

const char* TrajectoryFormatName(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum: return "tum";
    case TrajectoryFormat::kKitti: return "kitti";
    case TrajectoryFormat::kEuroc: return "euroc";
  }
  return "?";
}

Status ReadTrajectory(const std::string& path, TrajectoryFormat format, Trajectory* out,
                      const std::string& times_path) {
  if (!times_path.empty() && format != TrajectoryFormat::kKitti) {
    return Status::Error(path + ": a times file is only used with the KITTI format");
  }
  std::vector<std::pair<int, std::string>> lines;
  if (Status s = ForEachDataLine(path, &lines); !s) return s;
  if (lines.empty()) return Status::Error(path + ": no poses (only comments or empty lines)");
  Trajectory traj(lines.size());
  for (size_t i = 0; i < lines.size(); ++i) {
    const auto& [line, text] = lines[i];
    Status s;
    if (format == TrajectoryFormat::kTum) s = ParseTumLine(path, line, text, &traj[i]);
    if (format == TrajectoryFormat::kKitti) s = ParseKittiLine(path, line, text, &traj[i]);
    if (format == TrajectoryFormat::kEuroc) s = ParseEurocLine(path, line, text, &traj[i]);
    if (!s) return s;
    if (format == TrajectoryFormat::kKitti) traj[i].t_s = static_cast<double>(i);
  }
  if (!times_path.empty()) {
    if (Status s = ReadTimes(times_path, &traj); !s) return s;
  } else if (Status s = CheckOrder(path, lines, traj); !s) {
    return s;
  }
  *out = std::move(traj);
  return Status::Ok();
}

Status WriteTrajectory(const std::string& path, TrajectoryFormat format, const Trajectory& traj) {
  std::ofstream os(path);
  if (!os) return Status::Error(path + ": cannot open for writing");
  os << std::setprecision(kDigits);
  if (format == TrajectoryFormat::kTum) WriteTum(os, traj);
  if (format == TrajectoryFormat::kKitti) WriteKitti(os, traj);
  if (format == TrajectoryFormat::kEuroc) WriteEuroc(os, traj);
  os.flush();
  if (!os) return Status::Error(path + ": write failed");
  return Status::Ok();
}

Status WriteKittiTimes(const std::string& path, const Trajectory& traj) {
  std::ofstream os(path);
  if (!os) return Status::Error(path + ": cannot open for writing");
  os << std::setprecision(kDigits);
  for (const auto& sp : traj) os << sp.t_s << '\n';
  os.flush();
  if (!os) return Status::Error(path + ": write failed");
  return Status::Ok();
}

}  // namespace rotolidar
