#include "bench/calib/calib_data.hpp"

#include <cmath>
#include <cstdlib>

#include "core/deskew/rotary.hpp"
#include "core/wire/vlp16.hpp"
#include "core/util/validation.hpp"

namespace rotolidar::bench {
namespace {

/// Mean gyro and accel of the samples with t in [t0, t0 + window); false when there is none.
bool WindowMean(const std::vector<ImuSample>& imu, std::size_t* cursor, double t0, double window_s,
                Eigen::Vector3d* gyro, Eigen::Vector3d* accel) {
  gyro->setZero(), accel->setZero();
  std::size_t n = 0, i = *cursor;
  while (i < imu.size() && imu[i].t_s < t0) ++i;
  *cursor = i;
  for (; i < imu.size() && imu[i].t_s < t0 + window_s; ++i, ++n) {
    *gyro += imu[i].gyro_radps;
    *accel += imu[i].accel_mps2;
  }
  if (n == 0) return false;
  *gyro /= double(n), *accel /= double(n);
  return true;
}

}  // namespace

bool StaticSpanOptions::Validate(std::string* error) const {
  if (!(window_s > 0.0 && window_s <= 10.0)) return FailValidation(error, "static span: window_s must be in (0, 10] s");
  if (!(gyro_threshold_radps > 0.0)) return FailValidation(error, "static span: gyro_threshold_radps must be > 0");
  if (!(accel_threshold_mps2 > 0.0)) return FailValidation(error, "static span: accel_threshold_mps2 must be > 0");
  if (!(margin_s >= 0.0)) return FailValidation(error, "static span: margin_s must be >= 0");
  return true;
}

bool RotorPointOptions::Validate(std::string* error) const {
  if (!(min_range_m >= 0.0 && max_range_m > min_range_m))
    return FailValidation(error, "points: need 0 <= min_range_m < max_range_m");
  if (max_points < 1000) return FailValidation(error, "points: max_points must be >= 1000");
  return true;
}

Status DetectStaticSpan(const std::vector<ImuSample>& imu, const StaticSpanOptions& options, TimeSpan* span) {
  std::string why;
  if (!options.Validate(&why)) return Status::Error(why);
  if (imu.size() < 2 || imu.back().t_s - imu.front().t_s < 2.0 * options.window_s)
    return Status::Error("static span: the IMU stream is shorter than two windows of " +
                         std::to_string(options.window_s) + " s");
  const double t0 = imu.front().t_s;
  std::size_t cursor = 0;
  Eigen::Vector3d gyro0, accel0, gyro, accel;
  if (!WindowMean(imu, &cursor, t0, options.window_s, &gyro0, &accel0))
    return Status::Error("static span: no IMU sample in the first window");
  double end = t0 + options.window_s;
  for (double t = end; t + options.window_s <= imu.back().t_s; t += options.window_s) {
    if (!WindowMean(imu, &cursor, t, options.window_s, &gyro, &accel)) break;  // a gap ends the span
    if ((gyro - gyro0).norm() > options.gyro_threshold_radps ||
        (accel - accel0).norm() > options.accel_threshold_mps2)
      break;
    end = t + options.window_s;
  }
  span->t_start_s = t0;
  span->t_end_s = end - options.margin_s;
  if (span->length_s() < options.window_s)
    return Status::Error("static span: the base moves from the start (static for less than " +
                         std::to_string(options.window_s + options.margin_s) + " s); give --static-span");
  return Status::Ok();
}

Status ParseTimeSpan(const std::string& text, TimeSpan* span) {
  const std::size_t colon = text.find(':');
  const std::string bad = "time span '" + text + "': expected A:B in seconds with A < B";
  if (colon == std::string::npos) return Status::Error(bad);
  char* end = nullptr;
  const std::string a = text.substr(0, colon), b = text.substr(colon + 1);
  const double t0 = std::strtod(a.c_str(), &end);
  if (a.empty() || *end != '\0') return Status::Error(bad);
  const double t1 = std::strtod(b.c_str(), &end);
  if (b.empty() || *end != '\0' || !(t1 > t0) || !std::isfinite(t0) || !std::isfinite(t1)) return Status::Error(bad);
  span->t_start_s = t0, span->t_end_s = t1;
  return Status::Ok();
}

Status LoadRotorPoints(const Recording& rec, const RigCalib& calib, const TimeSpan& span,
                       const RotorPointOptions& options, std::vector<RotorPoint>* points) {
  std::string why;
  if (!options.Validate(&why)) return Status::Error(why);
  RotorAngleInterpolator rotor(calib);
  for (const EncoderSample& e : rec.encoder) rotor.Add(e);
  Vlp16DecoderConfig dc;
  dc.min_range_m = calib.lidar.min_range_m;
  dc.max_range_m = calib.lidar.max_range_m;
  dc.lidar_clock_offset_s = calib.lidar_clock_offset_s;
  Vlp16Decoder decoder(calib.lidar, dc);
  std::vector<LidarPoint> decoded;
  std::vector<RotorPoint> all;
  for (std::size_t i = 0; i < rec.lidar_packets.size(); ++i) {
    decoded.clear();
    if (Status s = decoder.Decode(rec.lidar_packets[i], &decoded); !s)
      return Status::Error(rec.dir + "/lidar.pcap: packet " + std::to_string(i) + ": " + s.message);
    for (const LidarPoint& p : decoded) {
      if (p.t_s < span.t_start_s || p.t_s > span.t_end_s || !rotor.Covers(p.t_s)) continue;
      const Eigen::Vector3f v(p.x_m, p.y_m, p.z_m);
      const double range = v.norm();
      if (!(range >= options.min_range_m && range <= options.max_range_m)) continue;
      constexpr double kHalfSpanS = 0.02;
      const double omega = (rotor.AngleAt(p.t_s + kHalfSpanS) - rotor.AngleAt(p.t_s - kHalfSpanS)) / (2 * kHalfSpanS);
      all.push_back({v, rotor.AngleAt(p.t_s), p.t_s, omega});
    }
  }
  const std::size_t stride = all.size() / options.max_points + 1;
  points->clear();
  for (std::size_t i = 0; i < all.size(); i += stride) points->push_back(all[i]);
  if (points->empty())
    return Status::Error(rec.dir + ": no LiDAR point with an encoder angle in the span " +
                         std::to_string(span.t_start_s) + ".." + std::to_string(span.t_end_s) + " s");
  return Status::Ok();
}

}  // namespace rotolidar::bench
