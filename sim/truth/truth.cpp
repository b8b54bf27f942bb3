#include "sim/truth/truth.hpp"

#include <charconv>
#include <filesystem>
#include <string_view>
#include <system_error>
#include <type_traits>

#include <Eigen/Geometry>

namespace rotolidar::sim {
namespace {

namespace fs = std::filesystem;

constexpr const char* kRotorHeader = "t_s,theta_rad";
constexpr const char* kImuBiasHeader = "t_s,bgx,bgy,bgz,bax,bay,baz";
constexpr const char* kDynamicHitsHeader = "t_s,object_id,x_m,y_m,z_m";

/// Appends `values` separated by `sep` and a newline, each in shortest round-trip form.
void WriteRow(std::ofstream& out, const double* values, int n, char sep) {
  std::string line;
  char buf[32];
  for (int i = 0; i < n; ++i) {
    if (i > 0) line.push_back(sep);
    const auto res = std::to_chars(buf, buf + sizeof(buf), values[i]);
    line.append(buf, res.ptr);
  }
  line.push_back('\n');
  out << line;
}

void WritePoseRow(std::ofstream& out, const StampedPose& p) {
  Eigen::Quaterniond q(p.T_ref_body.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const Eigen::Vector3d t = p.T_ref_body.translation();
  const double v[8] = {p.t_s, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
  WriteRow(out, v, 8, ' ');
}

/// Splits `line` on `sep` (or on runs of blanks when sep == ' ') into exactly `n` doubles. On failure returns
/// the 0-based index of the bad field (n when the count is wrong).
int ParseRow(std::string_view line, char sep, int n, double* out) {
  int field = 0;
  size_t pos = 0;
  while (pos <= line.size()) {
    if (sep == ' ')
      while (pos < line.size() && (line[pos] == ' ' || line[pos] == '\t')) ++pos;
    if (pos == line.size() && sep == ' ') break;
    size_t end = sep == ' ' ? line.find_first_of(" \t", pos) : line.find(sep, pos);
    if (end == std::string_view::npos) end = line.size();
    if (field >= n) return n;
    const auto res = std::from_chars(line.data() + pos, line.data() + end, out[field]);
    if (res.ec != std::errc() || res.ptr != line.data() + end) return field;
    ++field;
    pos = end + 1;
  }
  return field == n ? -1 : n;
}

Status RowError(const std::string& path, int line_no, int bad_field, int n, const char* const* names) {
  std::string msg = path + ":" + std::to_string(line_no) + ": ";
  if (bad_field >= n)
    msg += "expected " + std::to_string(n) + " fields";
  else
    msg += std::string("bad number in field '") + names[bad_field] + "'";
  return Status::Error(msg);
}

/// Reads lines of `n` numbers; '#' comments and blank lines are skipped, as is a first line equal to `header`.
/// on_row(values) may return an int: the index of a field whose value it rejects (-1 = accepted).
template <typename OnRow>
Status ReadRows(const std::string& path, char sep, int n, const char* const* names, const char* header,
                OnRow on_row) {
  std::ifstream in(path);
  if (!in) return Status::Error(path + ": cannot open for reading");
  std::string line;
  int line_no = 0;
  double v[8];
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    if (header && line_no == 1) {
      if (line != header) return Status::Error(path + ":1: expected header '" + header + "'");
      continue;
    }
    const int bad = ParseRow(line, sep, n, v);
    if (bad >= 0) return RowError(path, line_no, bad, n, names);
    if constexpr (std::is_same_v<decltype(on_row(v)), int>) {
      if (const int invalid = on_row(v); invalid >= 0)
        return Status::Error(path + ":" + std::to_string(line_no) + ": bad value in field '" + names[invalid] + "'");
    } else {
      on_row(v);
    }
  }
  if (in.bad()) return Status::Error(path + ": read error");
  return Status::Ok();
}

}  // namespace

Status TruthWriter::Open(const std::string& recording_dir) {
  if (open_) return Status::Error("TruthWriter: already open on " + dir_);
  dir_ = (fs::path(recording_dir) / "truth").string();
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) return Status::Error(dir_ + ": cannot create directory: " + ec.message());
  File* files[] = {&base_, &lidar_, &rotor_, &imu_bias_, &cam_, &dynamic_hits_};
  const char* names[] = {"base.tum", "lidar.tum", "rotor.csv", "imu_bias.csv", "cam.tum", "dynamic_hits.csv"};
  for (int i = 0; i < 6; ++i) {
    files[i]->path = (fs::path(dir_) / names[i]).string();
    files[i]->stream.open(files[i]->path, std::ios::out | std::ios::trunc);
    if (!files[i]->stream) return Status::Error(files[i]->path + ": cannot open for writing");
  }
  base_.stream << "# T_world_base: t_s tx ty tz qx qy qz qw\n";
  lidar_.stream << "# T_world_lidar: t_s tx ty tz qx qy qz qw\n";
  cam_.stream << "# T_world_cam (camera optical frame, mid-exposure): t_s tx ty tz qx qy qz qw\n";
  rotor_.stream << kRotorHeader << "\n";
  imu_bias_.stream << kImuBiasHeader << "\n";
  dynamic_hits_.stream << kDynamicHitsHeader << "\n";
  open_ = true;
  return Status::Ok();
}

Status TruthWriter::Check(File& file) {
  if (!open_) return Status::Error("TruthWriter: not open");
  if (!file.stream) return Status::Error(file.path + ": write failed");
  return Status::Ok();
}

Status TruthWriter::WriteBase(const StampedPose& T_world_base) {
  if (open_) WritePoseRow(base_.stream, T_world_base);
  return Check(base_);
}

Status TruthWriter::WriteLidar(const StampedPose& T_world_lidar) {
  if (open_) WritePoseRow(lidar_.stream, T_world_lidar);
  return Check(lidar_);
}

Status TruthWriter::WriteCam(const StampedPose& T_world_cam) {
  if (open_) WritePoseRow(cam_.stream, T_world_cam);
  return Check(cam_);
}

Status TruthWriter::WriteRotor(const RotorAngleSample& s) {
  const double v[2] = {s.t_s, s.theta_rad};
  if (open_) WriteRow(rotor_.stream, v, 2, ',');
  return Check(rotor_);
}

Status TruthWriter::WriteImuBias(const ImuBiasSample& s) {
  const Eigen::Vector3d& g = s.gyro_bias_radps;
  const Eigen::Vector3d& a = s.accel_bias_mps2;
  const double v[7] = {s.t_s, g.x(), g.y(), g.z(), a.x(), a.y(), a.z()};
  if (open_) WriteRow(imu_bias_.stream, v, 7, ',');
  return Check(imu_bias_);
}

Status TruthWriter::WriteDynamicHit(const DynamicHitSample& s) {
  const Eigen::Vector3d& p = s.p_world;
  const double v[5] = {s.t_s, static_cast<double>(s.object_id), p.x(), p.y(), p.z()};
  if (open_) WriteRow(dynamic_hits_.stream, v, 5, ',');
  return Check(dynamic_hits_);
}

Status TruthWriter::Close() {
  if (!open_) return Status::Error("TruthWriter: not open");
  Status first = Status::Ok();
  for (File* f : {&base_, &lidar_, &rotor_, &imu_bias_, &cam_, &dynamic_hits_}) {
    f->stream.flush();
    const bool ok = static_cast<bool>(f->stream);
    f->stream.close();
    if ((!ok || f->stream.fail()) && first.ok) first = Status::Error(f->path + ": write failed on close");
  }
  open_ = false;
  return first;
}

Status WriteTruth(const std::string& recording_dir, const TruthLog& log) {
  TruthWriter w;
  Status s = w.Open(recording_dir);
  for (const auto& p : log.base)
    if (s.ok) s = w.WriteBase(p);
  for (const auto& p : log.lidar)
    if (s.ok) s = w.WriteLidar(p);
  for (const auto& r : log.rotor)
    if (s.ok) s = w.WriteRotor(r);
  for (const auto& b : log.imu_bias)
    if (s.ok) s = w.WriteImuBias(b);
  for (const auto& p : log.cam)
    if (s.ok) s = w.WriteCam(p);
  for (const auto& h : log.dynamic_hits)
    if (s.ok) s = w.WriteDynamicHit(h);
  if (!w.is_open()) return s;
  const Status c = w.Close();
  return s.ok ? c : s;
}

Status ReadTum(const std::string& path, Trajectory* out) {
  static const char* const kNames[] = {"t", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  out->clear();
  return ReadRows(path, ' ', 8, kNames, nullptr, [out](const double* v) {
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    out->push_back({v[0], MakePose(Eigen::Vector3d(v[1], v[2], v[3]), q)});
  });
}

Status ReadTruth(const std::string& recording_dir, TruthLog* out) {
  static const char* const kRotorNames[] = {"t_s", "theta_rad"};
  static const char* const kBiasNames[] = {"t_s", "bgx", "bgy", "bgz", "bax", "bay", "baz"};
  const fs::path dir = fs::path(recording_dir) / "truth";
  *out = TruthLog{};
  Status s = ReadTum((dir / "base.tum").string(), &out->base);
  if (s.ok) s = ReadTum((dir / "lidar.tum").string(), &out->lidar);
  if (s.ok)
    s = ReadRows((dir / "rotor.csv").string(), ',', 2, kRotorNames, kRotorHeader,
                 [out](const double* v) { out->rotor.push_back({v[0], v[1]}); });
  if (s.ok)
    s = ReadRows((dir / "imu_bias.csv").string(), ',', 7, kBiasNames, kImuBiasHeader, [out](const double* v) {
      out->imu_bias.push_back({v[0], Eigen::Vector3d(v[1], v[2], v[3]), Eigen::Vector3d(v[4], v[5], v[6])});
    });
  if (s.ok && fs::exists(dir / "cam.tum")) s = ReadTum((dir / "cam.tum").string(), &out->cam);
  if (s.ok) s = ReadDynamicHits(recording_dir, &out->dynamic_hits);
  return s;
}

Status ReadDynamicHits(const std::string& recording_dir, std::vector<DynamicHitSample>* out) {
  static const char* const kNames[] = {"t_s", "object_id", "x_m", "y_m", "z_m"};
  const fs::path path = fs::path(recording_dir) / "truth" / "dynamic_hits.csv";
  out->clear();
  if (!fs::exists(path)) return Status::Ok();
  return ReadRows(path.string(), ',', 5, kNames, kDynamicHitsHeader, [out](const double* v) {
    // An object index: a whole number in int's range (written as one by WriteDynamicHit).
    if (!(v[1] >= 0.0 && v[1] <= 2147483647.0) || v[1] != static_cast<double>(static_cast<int>(v[1]))) return 1;
    out->push_back({v[0], static_cast<int>(v[1]), Eigen::Vector3d(v[2], v[3], v[4])});
    return -1;
  });
}

}  // namespace rotolidar::sim
