// A KITTI odometry sequence folder, the dataset layout the writer uses, and the bin -> ScanPoint conversion
// (rings from the HDL-64E's scan-line order; docs/kitti.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/io/kitti.hpp"
#include "core/io/recording.hpp"

namespace rotolidar {
namespace {

namespace fs = std::filesystem;

/// True for names like "000042.bin"; *id = 42.
bool FrameIdOf(const fs::path& file, int* id) {
  const std::string stem = file.stem().string();
  if (stem.empty() || stem.size() > 9 || !std::all_of(stem.begin(), stem.end(), ::isdigit)) return false;
  *id = std::stoi(stem);
  return true;
}

Status ListBins(const std::string& velodyne_dir, KittiSequence* seq) {
  std::error_code ec;
  if (!fs::is_directory(velodyne_dir, ec)) return Status::Error(velodyne_dir + ": no such folder");
  std::vector<std::pair<int, std::string>> bins;
  for (const fs::directory_entry& e : fs::directory_iterator(velodyne_dir, ec)) {
    if (e.path().extension() != ".bin") continue;
    int id = 0;
    if (!FrameIdOf(e.path(), &id))
      return Status::Error(e.path().string() + ": a velodyne bin must be named by its frame number (%06d.bin)");
    bins.emplace_back(id, e.path().string());
  }
  if (ec) return Status::Error(velodyne_dir + ": cannot list: " + ec.message());
  if (bins.empty()) return Status::Error(velodyne_dir + ": no .bin files");
  std::sort(bins.begin(), bins.end());
  for (size_t i = 1; i < bins.size(); ++i)
    if (bins[i].first == bins[i - 1].first)
      return Status::Error(bins[i].second + ": frame " + std::to_string(bins[i].first) + " named twice");
  for (auto& [id, path] : bins) {
    seq->frame_ids.push_back(id);
    seq->bin_paths.push_back(std::move(path));
  }
  return Status::Ok();
}

/// The explicit path if given (it must exist), else the first existing default, else "" (absent).
Status Resolve(const std::string& given, const std::vector<std::string>& defaults, std::string* path) {
  std::error_code ec;
  if (!given.empty()) {
    if (!fs::is_regular_file(given, ec)) return Status::Error(given + ": no such file");
    *path = given;
    return Status::Ok();
  }
  path->clear();
  for (const std::string& d : defaults)
    if (fs::is_regular_file(d, ec)) {
      *path = d;
      break;
    }
  return Status::Ok();
}

Status CheckCovers(const std::string& path, size_t lines, const KittiSequence& seq) {
  const int last = seq.frame_ids.back();
  if (lines <= size_t(last))
    return Status::Error(path + ": " + std::to_string(lines) + " lines, but " + seq.bin_paths.back() +
                         " needs line " + std::to_string(last + 1));
  return Status::Ok();
}

/// With a velodyne_times/ folder: the time file of every bin (same name), which must exist.
Status ListPointTimes(const std::string& times_dir, KittiSequence* seq) {
  std::error_code ec;
  if (!fs::is_directory(times_dir, ec)) return Status::Ok();
  for (const std::string& bin : seq->bin_paths) {
    const std::string path = times_dir + "/" + fs::path(bin).filename().string();
    if (!fs::is_regular_file(path, ec))
      return Status::Error(path + ": no such file: with a velodyne_times/ folder every bin needs its point times");
    seq->point_time_paths.push_back(path);
  }
  return Status::Ok();
}

/// The optional IMU: imu.csv and, required with it, calib_imu_to_velo.txt. Samples outside the frames' time span
/// are kept (the runner uses what it needs).
Status OpenImu(const KittiSequencePaths& paths, KittiSequence* seq) {
  if (Status s = Resolve(paths.imu_path, {paths.dir + "/imu.csv"}, &seq->imu_path); !s) return s;
  if (seq->imu_path.empty()) return Status::Ok();
  const std::string calib_default = paths.dir + "/calib_imu_to_velo.txt";
  if (Status s = Resolve(paths.imu_calib_path, {calib_default}, &seq->imu_calib_path); !s) return s;
  if (seq->imu_calib_path.empty())
    return Status::Error(calib_default + ": no such file (required with " + seq->imu_path +
                         ": it defines the IMU's frame)");
  if (Status s = ReadKittiImuCalib(seq->imu_calib_path, &seq->imu_calib); !s) return s;
  if (Status s = LoadImuCsv(seq->imu_path, &seq->imu); !s) return s;
  if (seq->imu.empty()) return Status::Error(seq->imu_path + ": no samples");
  return Status::Ok();
}

std::string SequenceName(const std::string& dir) {
  fs::path p = fs::absolute(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  return p.filename().string();
}

}  // namespace

Status OpenKittiSequence(const KittiSequencePaths& paths, KittiSequence* sequence) {
  if (paths.dir.empty()) return Status::Error("KITTI sequence: no folder given");
  KittiSequence seq;
  if (Status s = ListBins(paths.dir + "/velodyne", &seq); !s) return s;
  const std::string calib_default = paths.dir + "/calib.txt";
  if (Status s = Resolve(paths.calib_path, {calib_default}, &seq.calib_path); !s) return s;
  if (seq.calib_path.empty()) return Status::Error(calib_default + ": no such file (calib.txt is required)");
  if (Status s = ReadKittiCalib(seq.calib_path, &seq.calib); !s) return s;

  if (Status s = Resolve(paths.times_path, {paths.dir + "/times.txt"}, &seq.times_path); !s) return s;
  if (seq.times_path.empty()) {
    seq.nominal_times = true;
    for (int id = 0; id <= seq.frame_ids.back(); ++id) seq.times.push_back(0.1 * id);
  } else {
    if (Status s = ReadKittiTimeList(seq.times_path, &seq.times); !s) return s;
    if (Status s = CheckCovers(seq.times_path, seq.times.size(), seq); !s) return s;
  }

  const std::vector<std::string> pose_defaults = {
      paths.dir + "/poses.txt", paths.dir + "/../../poses/" + SequenceName(paths.dir) + ".txt"};
  if (Status s = Resolve(paths.poses_path, pose_defaults, &seq.poses_path); !s) return s;
  if (!seq.poses_path.empty()) {
    if (Status s = ReadKittiPoses(seq.poses_path, &seq.poses); !s) return s;
    if (Status s = CheckCovers(seq.poses_path, seq.poses.size(), seq); !s) return s;
  }
  if (Status s = ListPointTimes(paths.dir + "/velodyne_times", &seq); !s) return s;
  const std::string info_path = paths.dir + "/sequence_info.txt";
  std::error_code ec;
  if (fs::is_regular_file(info_path, ec)) {
    if (Status s = ReadKittiSequenceInfo(info_path, &seq.info); !s) return s;
    seq.info_path = info_path;
  }
  if (Status s = OpenImu(paths, &seq); !s) return s;
  *sequence = std::move(seq);
  return Status::Ok();
}

std::string KittiDatasetLayout::BinPath(int frame_id) const {
  char name[32];
  std::snprintf(name, sizeof(name), "%06d.bin", frame_id);
  return SequenceDir() + "/velodyne/" + name;
}

std::string KittiDatasetLayout::PointTimesPath(int frame_id) const {
  char name[32];
  std::snprintf(name, sizeof(name), "%06d.bin", frame_id);
  return SequenceDir() + "/velodyne_times/" + name;
}

Status CreateKittiDatasetFolders(const KittiDatasetLayout& layout, bool point_times) {
  std::vector<std::string> dirs = {layout.SequenceDir() + "/velodyne", layout.root + "/poses"};
  if (point_times) dirs.push_back(layout.SequenceDir() + "/velodyne_times");
  for (const std::string& dir : dirs) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return Status::Error(dir + ": cannot create folder: " + ec.message());
  }
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------------------------

bool KittiScanConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (!(line_break_deg > 0.0 && line_break_deg < 360.0)) return fail("kitti.line_break_deg must be in (0, 360)");
  if (expected_lines < 0 || expected_lines > 256)
    return fail("kitti.expected_lines must be in [0, 256] (0: the sequence's)");
  if (!(scan_period_s > 0.0 && std::isfinite(scan_period_s))) return fail("kitti.scan_period_s must be > 0");
  return true;
}

namespace {

/// Counter-clockwise azimuth of (x, y) in [0, 360) as a float (never rounds up to 360).
float AzimuthCcwDeg(float x, float y) {
  double a = std::atan2(double(y), double(x)) * (180.0 / M_PI);
  if (a < 0.0) a += 360.0;
  if (a >= 360.0) a -= 360.0;
  const float f = float(a);
  return f >= 360.f ? std::nextafter(360.f, 0.f) : f;
}

float Median(std::vector<float>* v) {
  if (v->empty()) return std::nanf("");
  std::nth_element(v->begin(), v->begin() + long(v->size() / 2), v->end());
  return (*v)[v->size() / 2];
}

bool IsFinite(const KittiPoint& p) {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.z_m) && std::isfinite(p.reflectance);
}

/// Per bin point: its scan line (-1: dropped as non-finite), azimuth [deg] and time [s].
struct LineSplit {
  std::vector<int> line;
  std::vector<float> az;
  std::vector<double> t_s;
};

/// Line medians of the elevation, the line-count limit, the elevation check (azimuth split only) and the
/// ScanPoints: ring = lines - 1 - line (the top line is stored first).
Status MakeScanPoints(const std::vector<KittiPoint>& bin, const LineSplit& split, KittiScanStats* st,
                      std::vector<ScanPoint>* points) {
  if (st->num_lines > 256)
    return Status::Error("KITTI bin: " + std::to_string(st->num_lines) + " scan lines (> 256): the points are not " +
                         "stored line by line" + (st->lines_from_times ? "" : " by azimuth (a bin in another order, "
                         "e.g. a rotolidar export, needs its per-point times in velodyne_times/)"));
  std::vector<std::vector<float>> elevations(st->num_lines);
  for (size_t i = 0; i < bin.size(); ++i)
    if (split.line[i] >= 0)
      elevations[size_t(split.line[i])].push_back(
          float(std::atan2(double(bin[i].z_m), std::hypot(double(bin[i].x_m), double(bin[i].y_m))) * 180.0 / M_PI));
  for (auto& e : elevations) st->line_median_elevation_deg.push_back(Median(&e));
  for (size_t l = 1; l < st->num_lines && !st->lines_from_times; ++l)
    st->elevation_inversions += st->line_median_elevation_deg[l] > st->line_median_elevation_deg[l - 1] ? 1 : 0;
  std::vector<ScanPoint> out;
  out.reserve(bin.size() - st->num_nonfinite);
  for (size_t i = 0; i < bin.size(); ++i) {
    if (split.line[i] < 0) continue;
    ScanPoint sp;
    sp.p_base = Eigen::Vector3f(bin[i].x_m, bin[i].y_m, bin[i].z_m);
    sp.range_m = sp.p_base.norm();
    sp.azimuth_deg = split.az[i];
    sp.intensity = 255.f * bin[i].reflectance;
    sp.ring = uint8_t(int(st->num_lines) - 1 - split.line[i]);
    sp.t_s = split.t_s[i];
    out.push_back(sp);
  }
  *points = std::move(out);
  return Status::Ok();
}

}  // namespace

// A line ends where the azimuth falls back to ~0 (the HDL-64E's order).
Status KittiScanPoints(const std::vector<KittiPoint>& bin, Seconds t_frame_s, const KittiScanConfig& config,
                       std::vector<ScanPoint>* points, KittiScanStats* stats) {
  std::string why;
  if (!config.Validate(&why)) return Status::Error(why);
  KittiScanStats st;
  st.num_input = bin.size();
  LineSplit split{std::vector<int>(bin.size(), -1), std::vector<float>(bin.size()), std::vector<double>(bin.size())};
  int current = -1;
  float prev_az = 0.f;
  for (size_t i = 0; i < bin.size(); ++i) {
    if (!IsFinite(bin[i])) {
      ++st.num_nonfinite;
      continue;
    }
    const float az = AzimuthCcwDeg(bin[i].x_m, bin[i].y_m);
    if (current < 0 || double(prev_az) - double(az) > config.line_break_deg) ++current;
    split.line[i] = current;
    split.az[i] = az;
    split.t_s[i] = t_frame_s + config.scan_period_s * double(az) / 360.0;
    prev_az = az;
  }
  st.num_lines = size_t(current + 1);
  if (Status s = MakeScanPoints(bin, split, &st, points); !s) return s;
  if (stats) *stats = std::move(st);
  return Status::Ok();
}

// A line ends where the point time falls back (each line is stored in firing order).
Status KittiScanPoints(const std::vector<KittiPoint>& bin, const std::vector<float>& point_times_s,
                       Seconds t_frame_s, const KittiScanConfig& config, std::vector<ScanPoint>* points,
                       KittiScanStats* stats) {
  std::string why;
  if (!config.Validate(&why)) return Status::Error(why);
  if (point_times_s.size() != bin.size())
    return Status::Error("KITTI bin of " + std::to_string(bin.size()) + " points has " +
                         std::to_string(point_times_s.size()) + " point times");
  KittiScanStats st;
  st.num_input = bin.size();
  st.lines_from_times = true;
  LineSplit split{std::vector<int>(bin.size(), -1), std::vector<float>(bin.size()), std::vector<double>(bin.size())};
  int current = -1;
  float prev_t = 0.f;
  for (size_t i = 0; i < bin.size(); ++i) {
    const float t = point_times_s[i];
    if (!IsFinite(bin[i]) || !std::isfinite(t)) {
      ++st.num_nonfinite;
      continue;
    }
    if (current < 0 || t < prev_t) ++current;
    split.line[i] = current;
    double az = std::fmod(360.0 * double(t) / config.scan_period_s, 360.0);
    if (az < 0.0) az += 360.0;
    split.az[i] = std::min(float(az), std::nextafter(360.f, 0.f));
    split.t_s[i] = t_frame_s + double(t);
    prev_t = t;
  }
  st.num_lines = size_t(current + 1);
  if (Status s = MakeScanPoints(bin, split, &st, points); !s) return s;
  if (stats) *stats = std::move(st);
  return Status::Ok();
}

}  // namespace rotolidar

