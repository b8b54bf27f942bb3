// Sensor clocks and host capture jitter (sim/sensors/sensor_clock.hpp).
#include "sim/sensors/sensor_clock.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/util/validation.hpp"

namespace rotolidar::sim {

bool SensorClock::Validate(const std::string& name, std::string* error) const {
  if (!std::isfinite(offset_s) || std::abs(offset_s) > 1.0)
    return FailValidation(error, name + "_offset_s must be finite with |offset| <= 1 s");
  if (!std::isfinite(drift_ppm) || std::abs(drift_ppm) > 1000.0)
    return FailValidation(error, name + "_drift_ppm must be finite with |drift| <= 1000 ppm");
  return true;
}

bool CaptureJitterConfig::Validate(const std::string& name, std::string* error) const {
  if (!std::isfinite(latency_s) || latency_s < 0.0 || latency_s > 0.01)
    return FailValidation(error, name + "_latency_s must be finite and in [0, 0.01] s");
  if (!std::isfinite(jitter_scale_s) || jitter_scale_s < 0.0 || jitter_scale_s > 0.01)
    return FailValidation(error, name + "_jitter_scale_s must be finite and in [0, 0.01] s");
  return true;
}

CaptureJitter::CaptureJitter(const CaptureJitterConfig& config, uint64_t run_seed)
    : config_(config), stream_(run_seed, kCaptureJitterStream), last_s_(-std::numeric_limits<double>::infinity()) {}

Seconds CaptureJitter::Apply(Seconds t_arrival_s) {
  if (!config_.enabled()) return t_arrival_s;
  // Exponential by inversion: -scale * ln(1 - U), U in [0, 1) so the log's argument is in (0, 1].
  const double delay_s = config_.latency_s - config_.jitter_scale_s * std::log1p(-stream_.Uniform());
  last_s_ = std::max(last_s_, t_arrival_s + delay_s);
  return last_s_;
}

}  // namespace rotolidar::sim
