// The KITTI companion files rotolidar adds: per-point times (velodyne_times/%06d.bin) and sequence_info.txt
// (contracts in kitti.hpp).
#include <cstdint>
#include <fstream>
#include <utility>

#include "core/io/kitti.hpp"
#include "core/io/kitti_text.hpp"
#include "core/util/text.hpp"

namespace rotolidar {

using namespace kitti_text;

Status ReadKittiPointTimes(const std::string& path, std::vector<float>* times_s) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return Status::Error(path + ": cannot open");
  const std::streamoff size = in.tellg();
  if (size < 0) return Status::Error(path + ": cannot tell the file size");
  if (size % 4 != 0)
    return Status::Error(path + ": " + std::to_string(size) + " bytes is not a whole number of float32 times: a " +
                         "partial value starts at byte offset " + std::to_string(size - size % 4));
  std::vector<float> out(size_t(size / 4));
  in.seekg(0);
  if (!out.empty() && !in.read(reinterpret_cast<char*>(out.data()), size))
    return Status::Error(path + ": read error after byte offset " + std::to_string(in.gcount()));
  *times_s = std::move(out);
  return Status::Ok();
}

Status WriteKittiPointTimes(const std::string& path, const std::vector<float>& times_s) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return Status::Error(path + ": cannot create");
  out.write(reinterpret_cast<const char*>(times_s.data()), std::streamsize(times_s.size() * sizeof(float)));
  out.close();
  return out ? Status::Ok() : Status::Error(path + ": write failed");
}

namespace {

/// The text fields by key, in the order they are written (scan_lines is separate: it is a number).
std::vector<std::pair<const char*, std::string*>> TextFields(KittiSequenceInfo* info) {
  return {{"sensor", &info->sensor},         {"point_order", &info->point_order},
          {"point_times", &info->point_times}, {"frame", &info->frame},
          {"deskew", &info->deskew},         {"returns", &info->returns},
          {"source", &info->source}};
}

Status ParseScanLines(const std::string& path, int line, const std::string& value, int* scan_lines) {
  double v = 0.0;
  if (!ParseNumber(value, &v) || v != double(int(v)) || v < 1 || v > 256)
    return Status::Error(Where(path, line) + "scan_lines = '" + value + "': expected an integer in 1..256");
  *scan_lines = int(v);
  return Status::Ok();
}

}  // namespace

Status ReadKittiSequenceInfo(const std::string& path, KittiSequenceInfo* info) {
  std::vector<std::string> lines;
  if (Status s = ReadLines(path, &lines); !s) return s;
  KittiSequenceInfo out;
  std::vector<std::string> seen;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line = int(i) + 1;
    const std::string text = TrimSpace(lines[i]);
    if (text.empty() || text[0] == '#') continue;
    const size_t colon = text.find(':');
    if (colon == std::string::npos) return Status::Error(Where(path, line) + "expected 'key: value', got '" + text + "'");
    const std::string key = TrimSpace(text.substr(0, colon)), value = TrimSpace(text.substr(colon + 1));
    for (const std::string& k : seen)
      if (k == key) return Status::Error(Where(path, line) + "key '" + key + "' given twice");
    seen.push_back(key);
    if (key == "scan_lines") {
      if (Status s = ParseScanLines(path, line, value, &out.scan_lines); !s) return s;
      continue;
    }
    if (key == "range_sigma_m") {
      if (!ParseNumber(value, &out.range_sigma_m) || !(out.range_sigma_m > 0.0))
        return Status::Error(Where(path, line) + "range_sigma_m = '" + value + "': expected a number > 0 [m]");
      continue;
    }
    if (key == "rotor_deg_per_scan") {
      if (!ParseNumber(value, &out.rotor_deg_per_scan) || !(out.rotor_deg_per_scan >= 0.0))
        return Status::Error(Where(path, line) + "rotor_deg_per_scan = '" + value + "': expected a number >= 0 [deg]");
      continue;
    }
    std::string* field = nullptr;
    for (auto& [name, target] : TextFields(&out)) field = key == name ? target : field;
    if (field == nullptr)
      return Status::Error(Where(path, line) + "unknown key '" + key + "' (sensor scan_lines range_sigma_m rotor_deg_per_scan " +
                           "point_order point_times frame deskew returns source)");
    *field = value;
  }
  *info = std::move(out);
  return Status::Ok();
}

Status WriteKittiSequenceInfo(const std::string& path, const KittiSequenceInfo& info) {
  KittiSequenceInfo copy = info;
  std::string text = "# What the producer states about this KITTI odometry sequence (docs/kitti.md).\n";
  const auto fields = TextFields(&copy);
  for (const auto& [name, value] : fields)
    if (value->find('\n') != std::string::npos)
      return Status::Error(path + ": " + name + ": a value must be one line");
  if (!copy.sensor.empty()) text += "sensor: " + copy.sensor + "\n";
  if (copy.scan_lines > 0) text += "scan_lines: " + std::to_string(copy.scan_lines) + "\n";
  if (copy.range_sigma_m > 0.0) text += "range_sigma_m: " + FormatNumber(copy.range_sigma_m) + "\n";
  if (copy.rotor_deg_per_scan > 0.0) text += "rotor_deg_per_scan: " + FormatNumber(copy.rotor_deg_per_scan) + "\n";
  for (size_t k = 1; k < fields.size(); ++k)
    if (!fields[k].second->empty()) text += std::string(fields[k].first) + ": " + *fields[k].second + "\n";
  return WriteText(path, text);
}

}  // namespace rotolidar
