#include "core/deskew/rotary.hpp"

#include <algorithm>
#include <cmath>

namespace rotolidar {

bool RotorAngleInterpolator::Add(const EncoderSample& sample) {
  if (!t_s_.empty() && sample.t_s <= t_s_.back()) return false;
  double theta = calib_.EncoderAngle(sample.count);
  if (!theta_rad_.empty()) {
    // Unwrap: choose the 2*pi branch closest to the previous angle.
    const double prev = theta_rad_.back();
    theta += 2.0 * M_PI * std::round((prev - theta) / (2.0 * M_PI));
  }
  t_s_.push_back(sample.t_s);
  theta_rad_.push_back(theta);
  return true;
}

RotorSegment RotorAngleInterpolator::SegmentAt(Seconds t_s, size_t hint) const {
  const size_t n = t_s_.size();
  size_t hi = hint != kNoHint && hint + 2 < n && t_s_[hint + 1] <= t_s && t_s < t_s_[hint + 2]
                  ? hint + 2
                  : size_t(std::upper_bound(t_s_.begin(), t_s_.end(), t_s) - t_s_.begin());
  hi = std::min(hi, n - 1);
  RotorSegment g;
  g.lo = hi == 0 ? 0 : hi - 1;
  g.t_lo_s = t_s_[g.lo], g.t_hi_s = t_s_[hi];
  g.theta_lo_rad = theta_rad_[g.lo] - angle_offset_rad_;
  g.rate_radps = hi == g.lo ? 0.0 : (theta_rad_[hi] - theta_rad_[g.lo]) / (t_s_[hi] - t_s_[g.lo]);
  return g;
}

double RotorAngleInterpolator::AngleAt(Seconds t_s, RotorAngleSource* source) const {
  const double w = calib_.motor_speed_radps;
  if (t_s_.empty()) {
    if (source) *source = RotorAngleSource::kUniformFallback;
    return w * t_s - angle_offset_rad_;
  }
  if (!Covers(t_s)) {
    if (source) *source = RotorAngleSource::kUniformFallback;
    const size_t i = t_s < t_s_.front() ? 0 : t_s_.size() - 1;
    return theta_rad_[i] - angle_offset_rad_ + w * (t_s - t_s_[i]);
  }
  if (source) *source = RotorAngleSource::kEncoder;
  const RotorSegment g = SegmentAt(t_s);
  return g.theta_lo_rad + (t_s - g.t_lo_s) * g.rate_radps;
}

void RotorAngleInterpolator::DropBefore(Seconds t_s) {
  const auto it = std::lower_bound(t_s_.begin(), t_s_.end(), t_s);
  const size_t n = it - t_s_.begin();
  if (n <= 1) return;
  t_s_.erase(t_s_.begin(), t_s_.begin() + (n - 1));
  theta_rad_.erase(theta_rad_.begin(), theta_rad_.begin() + (n - 1));
}

RotaryTransform::RotaryTransform(const RotorAngleInterpolator& rotor)
    : rotor_(rotor),
      R_rotor_lidar_(rotor.calib().T_rotor_lidar.linear()),
      R_base_motor_(rotor.calib().T_base_motor.linear()),
      t_rotor_lidar_(rotor.calib().T_rotor_lidar.translation()),
      t_base_motor_(rotor.calib().T_base_motor.translation()) {}

// T_base_lidar(theta) * p is applied as T_base_motor * (RotZ(theta) * (T_rotor_lidar * p)) (Apply): the fixed
// transforms stay fixed and the rotor turn is a 2D rotation, instead of composing two 4x4 poses per point.
void RotaryTransform::Seek(Seconds t_s) {
  segment_ = rotor_.SegmentAt(t_s, have_ ? segment_.lo : RotorAngleInterpolator::kNoHint);
  have_ = true;
  last_ = segment_.t_hi_s == rotor_.last_time_s();
  cos_lo_ = std::cos(segment_.theta_lo_rad), sin_lo_ = std::sin(segment_.theta_lo_rad);
}

}  // namespace rotolidar
