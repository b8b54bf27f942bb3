// Revolution splitting of decoded VLP-16 points (contract in scan_splitter.hpp).
#include "core/wire/scan_splitter.hpp"

#include <cmath>

namespace rotolidar {

RevolutionSplitter::RevolutionSplitter(double cut_azimuth_deg) {
  cut_deg_ = std::fmod(cut_azimuth_deg, 360.0);
  if (cut_deg_ < 0.0) cut_deg_ += 360.0;
}

double RevolutionSplitter::RelativeAzimuth(float azimuth_deg) const {
  double rel = static_cast<double>(azimuth_deg) - cut_deg_;  // decoded azimuths lie in [0, 360): one wrap at most
  if (rel < 0.0) rel += 360.0;
  if (rel >= 360.0) rel = std::fmod(rel, 360.0);  // only for out-of-contract input
  return rel;
}

bool RevolutionSplitter::Append(const LidarPoint& point) {
  const double rel = RelativeAzimuth(point.azimuth_deg);
  const bool crossed = last_rel_deg_ >= 0.0 && last_rel_deg_ - rel > 180.0 && !current_.points.empty();
  if (crossed) {
    ++crossings_;
    finished_ = std::move(current_);
    current_ = LidarScan();
    current_.points.reserve(finished_.points.size() + finished_.points.size() / 8);  // the next one is similar
  }
  last_rel_deg_ = rel;
  if (current_.points.empty()) current_.t_start_s = point.t_s;
  current_.t_end_s = point.t_s;
  current_.points.push_back(point);
  return crossed;
}

std::optional<LidarScan> RevolutionSplitter::Add(const LidarPoint& point) {
  if (!Append(point)) return std::nullopt;
  return std::move(finished_);
}

void RevolutionSplitter::Add(const std::vector<LidarPoint>& points, std::vector<LidarScan>* finished) {
  for (const LidarPoint& p : points) {
    if (Append(p)) finished->push_back(std::move(finished_));
  }
}

std::optional<LidarScan> RevolutionSplitter::Flush() {
  last_rel_deg_ = -1.0;
  if (current_.points.empty()) return std::nullopt;
  LidarScan scan = std::move(current_);
  current_ = LidarScan();
  return scan;
}

}  // namespace rotolidar
