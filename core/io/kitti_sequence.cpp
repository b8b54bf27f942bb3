// A KITTI odometry sequence folder, the dataset layout the writer uses, and the bin -> ScanPoint conversion
// (rings from the HDL-64E's scan-line order; docs/kitti.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/io/kitti.hpp"

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
  *sequence = std::move(seq);
  return Status::Ok();
}

std::string KittiDatasetLayout::BinPath(int frame_id) const {
  char name[32];
  std::snprintf(name, sizeof(name), "%06d.bin", frame_id);
  return SequenceDir() + "/velodyne/" + name;
}

Status CreateKittiDatasetFolders(const KittiDatasetLayout& layout) {
  for (const std::string& dir : {layout.SequenceDir() + "/velodyne", layout.root + "/poses"}) {
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
  if (expected_lines < 1 || expected_lines > 256) return fail("kitti.expected_lines must be in [1, 256]");
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

}  // namespace

Status KittiScanPoints(const std::vector<KittiPoint>& bin, Seconds t_frame_s, const KittiScanConfig& config,
                       std::vector<ScanPoint>* points, KittiScanStats* stats) {
  std::string why;
  if (!config.Validate(&why)) return Status::Error(why);
  KittiScanStats st;
  st.num_input = bin.size();
  // Pass 1: azimuth and scan line of every finite point (a line ends where the azimuth falls back to ~0).
  std::vector<float> az(bin.size());
  std::vector<int> line(bin.size(), -1);
  int current = -1;
  float prev_az = 0.f;
  for (size_t i = 0; i < bin.size(); ++i) {
    const KittiPoint& p = bin[i];
    if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.z_m) || !std::isfinite(p.reflectance)) {
      ++st.num_nonfinite;
      continue;
    }
    az[i] = AzimuthCcwDeg(p.x_m, p.y_m);
    if (current < 0 || double(prev_az) - double(az[i]) > config.line_break_deg) ++current;
    line[i] = current;
    prev_az = az[i];
  }
  st.num_lines = size_t(current + 1);
  if (st.num_lines > 256)
    return Status::Error("KITTI bin: " + std::to_string(st.num_lines) +
                         " scan lines (> 256): the points are not stored line by line");
  // Median elevation per line: the lines must descend (the HDL-64E's top beam is stored first).
  std::vector<std::vector<float>> elevations(st.num_lines);
  for (size_t i = 0; i < bin.size(); ++i)
    if (line[i] >= 0)
      elevations[size_t(line[i])].push_back(
          float(std::atan2(double(bin[i].z_m), std::hypot(double(bin[i].x_m), double(bin[i].y_m))) * 180.0 / M_PI));
  for (auto& e : elevations) st.line_median_elevation_deg.push_back(Median(&e));
  for (size_t l = 1; l < st.num_lines; ++l)
    st.elevation_inversions += st.line_median_elevation_deg[l] > st.line_median_elevation_deg[l - 1] ? 1 : 0;

  std::vector<ScanPoint> out;
  out.reserve(bin.size() - st.num_nonfinite);
  for (size_t i = 0; i < bin.size(); ++i) {
    if (line[i] < 0) continue;
    ScanPoint sp;
    sp.p_base = Eigen::Vector3f(bin[i].x_m, bin[i].y_m, bin[i].z_m);
    sp.range_m = sp.p_base.norm();
    sp.azimuth_deg = az[i];
    sp.intensity = 255.f * bin[i].reflectance;
    sp.ring = uint8_t(int(st.num_lines) - 1 - line[i]);
    sp.t_s = t_frame_s + config.scan_period_s * double(az[i]) / 360.0;
    out.push_back(sp);
  }
  *points = std::move(out);
  if (stats) *stats = std::move(st);
  return Status::Ok();
}

}  // namespace rotolidar
