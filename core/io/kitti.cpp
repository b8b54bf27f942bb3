// KITTI odometry files: bins, calib.txt, poses, times (the sequence folder and the ring assignment:
// kitti_sequence.cpp).
#include "core/io/kitti.hpp"

#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <type_traits>

#include "core/io/kitti_text.hpp"
#include "core/util/text.hpp"

static_assert(std::numeric_limits<float>::is_iec559 && sizeof(float) == 4, "KITTI bins are IEEE-754 float32");
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "KITTI bins are little-endian: a big-endian host must swap");
static_assert(sizeof(rotolidar::KittiPoint) == 16 && std::is_trivially_copyable_v<rotolidar::KittiPoint>,
              "KittiPoint must match the 16-byte record on disk");

namespace rotolidar {
namespace kitti_text {

std::string Where(const std::string& path, int line) { return FileLinePrefix(path, line); }

bool ParseNumber(const std::string& token, double* value) {
  const char* b = token.data();
  const char* e = b + token.size();
  if (b != e && *b == '+') ++b;
  const auto r = std::from_chars(b, e, *value);
  return r.ec == std::errc() && r.ptr == e && b != e && std::isfinite(*value);
}

std::string FormatNumber(double value) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), value);  // shortest round-trip form
  return std::string(buf, r.ptr);
}

Status ReadLines(const std::string& path, std::vector<std::string>* lines) {
  std::ifstream in(path);
  if (!in) return Status::Error(path + ": cannot open");
  lines->clear();
  std::string line;
  while (std::getline(in, line)) lines->push_back(line);
  if (in.bad()) return Status::Error(path + ": read error");
  return Status::Ok();
}

Status ParseNumbers(const std::string& path, int line, const std::vector<std::string>& tokens, size_t first,
                    size_t count, const std::string& what, std::vector<double>* values) {
  if (tokens.size() - first != count)
    return Status::Error(Where(path, line) + what + ": expected " + std::to_string(count) + " numbers, got " +
                         std::to_string(tokens.size() - first));
  values->resize(count);
  for (size_t i = 0; i < count; ++i)
    if (!ParseNumber(tokens[first + i], &(*values)[i]))
      return Status::Error(Where(path, line) + what + " field " + std::to_string(i) + " = '" + tokens[first + i] +
                           "': not a finite number");
  return Status::Ok();
}

Matrix34d ToMatrix34(const std::vector<double>& v) {
  Matrix34d M;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) M(r, c) = v[size_t(4 * r + c)];
  return M;
}

Status ToPose(const std::string& path, int line, const std::string& what, const Matrix34d& M, Pose3* pose) {
  const Eigen::Matrix3d R = M.leftCols<3>();
  if (((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3) || R.determinant() < 0)
    return Status::Error(Where(path, line) + what + ": the 3x3 block is not a rotation");
  Pose3 T = Pose3::Identity();
  T.matrix().topRows<3>() = M;  // kept exactly as written
  *pose = T;
  return Status::Ok();
}

std::string FormatRow(const Matrix34d& M) {
  std::string s;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) s += (s.empty() ? "" : " ") + FormatNumber(M(r, c));
  return s;
}

Status WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::trunc);
  out << text;
  out.close();
  return out ? Status::Ok() : Status::Error(path + ": write failed");
}

/// Number of lines that count: trailing empty lines are dropped; an empty line before the last content line is an
/// error naming it.
Status ContentLines(const std::string& path, std::vector<std::string>* lines) {
  while (!lines->empty() && SplitWhitespace(lines->back()).empty()) lines->pop_back();
  for (size_t i = 0; i < lines->size(); ++i)
    if (SplitWhitespace((*lines)[i]).empty())
      return Status::Error(Where(path, int(i) + 1) + "empty line (line k must be frame k)");
  if (lines->empty()) return Status::Error(path + ": no data");
  return Status::Ok();
}

}  // namespace kitti_text

using namespace kitti_text;

Status ReadKittiBin(const std::string& path, std::vector<KittiPoint>* points) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return Status::Error(path + ": cannot open");
  const std::streamoff size = in.tellg();
  if (size < 0) return Status::Error(path + ": cannot tell the file size");
  if (size % 16 != 0)
    return Status::Error(path + ": " + std::to_string(size) + " bytes is not a whole number of 16-byte points " +
                         "(x y z reflectance float32): a partial point starts at byte offset " +
                         std::to_string(size - size % 16));
  std::vector<KittiPoint> out(size_t(size / 16));
  in.seekg(0);
  if (!out.empty() && !in.read(reinterpret_cast<char*>(out.data()), size))
    return Status::Error(path + ": read error after byte offset " + std::to_string(in.gcount()));
  *points = std::move(out);
  return Status::Ok();
}

Status WriteKittiBin(const std::string& path, const std::vector<KittiPoint>& points) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return Status::Error(path + ": cannot create");
  out.write(reinterpret_cast<const char*>(points.data()), std::streamsize(points.size() * sizeof(KittiPoint)));
  out.close();
  return out ? Status::Ok() : Status::Error(path + ": write failed");
}

Status ReadKittiCalib(const std::string& path, KittiCalib* calib) {
  static const char* const kKeys[] = {"P0", "P1", "P2", "P3", "Tr"};
  std::vector<std::string> lines;
  if (Status s = ReadLines(path, &lines); !s) return s;
  KittiCalib out;
  bool seen[5] = {false, false, false, false, false};
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line = int(i) + 1;
    const std::vector<std::string> tokens = SplitWhitespace(lines[i]);
    if (tokens.empty()) continue;
    const std::string& head = tokens[0];
    if (head.size() < 2 || head.back() != ':')
      return Status::Error(Where(path, line) + "expected 'KEY: 12 numbers', got '" + head + "'");
    const std::string key = head.substr(0, head.size() - 1);
    int k = -1;
    for (int j = 0; j < 5; ++j) k = key == kKeys[j] ? j : k;
    if (k < 0) return Status::Error(Where(path, line) + "unknown key '" + key + "' (P0 P1 P2 P3 Tr)");
    if (seen[k]) return Status::Error(Where(path, line) + "key '" + key + "' given twice");
    seen[k] = true;
    std::vector<double> v;
    if (Status s = ParseNumbers(path, line, tokens, 1, 12, key, &v); !s) return s;
    if (k < 4) {
      out.P[size_t(k)] = ToMatrix34(v);
    } else if (Status s = ToPose(path, line, key, ToMatrix34(v), &out.T_cam0_velo); !s) {
      return s;
    }
  }
  for (int j = 0; j < 5; ++j)
    if (!seen[j]) return Status::Error(path + ": key '" + kKeys[j] + "' missing");
  *calib = out;
  return Status::Ok();
}

Status WriteKittiCalib(const std::string& path, const KittiCalib& calib) {
  std::string text;
  for (int j = 0; j < 4; ++j) text += "P" + std::to_string(j) + ": " + FormatRow(calib.P[size_t(j)]) + "\n";
  text += "Tr: " + FormatRow(calib.T_cam0_velo.matrix().topRows<3>()) + "\n";
  return WriteText(path, text);
}

Status ReadKittiPoses(const std::string& path, std::vector<Pose3>* poses) {
  std::vector<std::string> lines;
  if (Status s = ReadLines(path, &lines); !s) return s;
  if (Status s = ContentLines(path, &lines); !s) return s;
  std::vector<Pose3> out(lines.size());
  for (size_t i = 0; i < lines.size(); ++i) {
    std::vector<double> v;
    if (Status s = ParseNumbers(path, int(i) + 1, SplitWhitespace(lines[i]), 0, 12, "pose", &v); !s) return s;
    if (Status s = ToPose(path, int(i) + 1, "pose", ToMatrix34(v), &out[i]); !s) return s;
  }
  *poses = std::move(out);
  return Status::Ok();
}

Status WriteKittiPoses(const std::string& path, const std::vector<Pose3>& poses) {
  std::string text;
  for (const Pose3& T : poses) text += FormatRow(T.matrix().topRows<3>()) + "\n";
  return WriteText(path, text);
}

Status ReadKittiTimeList(const std::string& path, std::vector<Seconds>* times) {
  std::vector<std::string> lines;
  if (Status s = ReadLines(path, &lines); !s) return s;
  if (Status s = ContentLines(path, &lines); !s) return s;
  std::vector<Seconds> out(lines.size());
  for (size_t i = 0; i < lines.size(); ++i) {
    std::vector<double> v;
    if (Status s = ParseNumbers(path, int(i) + 1, SplitWhitespace(lines[i]), 0, 1, "time", &v); !s) return s;
    out[i] = v[0];
    if (i > 0 && out[i] < out[i - 1])
      return Status::Error(Where(path, int(i) + 1) + "time " + lines[i] + " is earlier than the line before");
  }
  *times = std::move(out);
  return Status::Ok();
}

Status WriteKittiTimeList(const std::string& path, const std::vector<Seconds>& times) {
  std::string text;
  for (Seconds t : times) text += FormatNumber(t) + "\n";
  return WriteText(path, text);
}

namespace {

/// The general 4x4 inverse, as KITTI's devkit takes it: KITTI's Tr is orthonormal only to ~1e-7, so the rigid
/// inverse (transposed rotation) would leave Tr * Tr^-1 that far from the identity.
Pose3 MatrixInverse(const Pose3& T) {
  Pose3 inv;
  inv.matrix() = T.matrix().inverse();
  return inv;
}

}  // namespace

Pose3 VeloToCam0Pose(const Pose3& T_cam0_velo, const Pose3& T_velo0_velok) {
  return Pose3(T_cam0_velo.matrix() * T_velo0_velok.matrix() * MatrixInverse(T_cam0_velo).matrix());
}

Pose3 Cam0ToVeloPose(const Pose3& T_cam0_velo, const Pose3& T_cam0_0_cam0_k) {
  return Pose3(MatrixInverse(T_cam0_velo).matrix() * T_cam0_0_cam0_k.matrix() * T_cam0_velo.matrix());
}

}  // namespace rotolidar
