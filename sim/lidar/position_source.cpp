// VLP-16 position packets on the sim clock (contract in position_source.hpp).
#include "sim/lidar/position_source.hpp"
#include "core/util/log.hpp"
#include "core/util/validation.hpp"

#include <cmath>

namespace rotolidar::sim {
namespace {

constexpr double kHourS = 3600.0;
constexpr uint8_t kPpsLocked = 2;

}  // namespace

double PpsLockedClockOffsetS(double epoch_unix_s) { return -std::fmod(epoch_unix_s, kHourS); }

bool Vlp16PositionConfig::Validate(std::string* error) const {
  if (!(rate_hz > 0.0 && rate_hz <= 1000.0)) return FailValidation(error, "rate_hz must be in (0, 1000]");
  if (!std::isfinite(t0_s)) return FailValidation(error, "t0_s must be finite");
  if (!(epoch_unix_s >= 0.0 && std::isfinite(epoch_unix_s))) return FailValidation(error, "epoch_unix_s must be >= 0");
  if (!std::isfinite(lidar_clock_offset_s)) return FailValidation(error, "lidar_clock_offset_s must be finite");
  if (!std::isfinite(clock_drift_ppm)) return FailValidation(error, "clock_drift_ppm must be finite");
  if (pps_status > 3) return FailValidation(error, "pps_status must be 0..3");
  if (!(latitude_deg >= -90.0 && latitude_deg <= 90.0)) return FailValidation(error, "latitude_deg must be in [-90, 90]");
  if (!(longitude_deg >= -180.0 && longitude_deg <= 180.0)) {
    return FailValidation(error, "longitude_deg must be in [-180, 180]");
  }
  if (!(transmit_latency_s >= 0.0 && transmit_latency_s < 0.1)) {
    return FailValidation(error, "transmit_latency_s must be in [0, 0.1)");
  }
  if (pps_status == kPpsLocked) {
    // Sensor clock (s past hour) = t - offset; UTC past the hour = epoch + t: equal mod 3600 s (to 1 us).
    double d = std::fmod(-lidar_clock_offset_s - epoch_unix_s, kHourS);
    if (d < 0.0) d += kHourS;
    if (std::min(d, kHourS - d) > 1e-6) {
      return FailValidation(error, "pps_status 2 (locked) needs lidar_clock_offset_s = -(epoch_unix_s mod 3600) = " +
                             std::to_string(PpsLockedClockOffsetS(epoch_unix_s)) + ", got " +
                             std::to_string(lidar_clock_offset_s));
    }
  }
  return true;
}

Vlp16PositionSource::Vlp16PositionSource(const Vlp16PositionConfig& config) : config_(config) {
  std::string error;
  ROTOLIDAR_CHECK(config_.Validate(&error), error);
}

Seconds Vlp16PositionSource::next_time_s() const {
  return config_.t0_s + static_cast<double>(next_index_) / config_.rate_hz;
}

std::size_t Vlp16PositionSource::EmitUntil(Seconds t_s, std::vector<LidarPacket>* out) {
  ROTOLIDAR_CHECK(out != nullptr, "EmitUntil needs an output");
  std::size_t n = 0;
  for (Seconds t = next_time_s(); t <= t_s; t = next_time_s()) {
    const std::string nmea =
        FormatGprmc(config_.epoch_unix_s + t, config_.gps_fix, config_.latitude_deg, config_.longitude_deg);
    const double offset_s = config_.lidar_clock_offset_s - config_.clock_drift_ppm * 1e-6 * t;  // drift as offset
    LidarPacket packet = EncodeVlp16PositionPacket(t, offset_s, config_.pps_status, nmea);
    packet.t_capture_s = t + config_.transmit_latency_s;
    out->push_back(std::move(packet));
    ++next_index_;
    ++n;
  }
  return n;
}

}  // namespace rotolidar::sim
