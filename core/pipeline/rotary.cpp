#include "core/pipeline/rotary.hpp"

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

double RotorAngleInterpolator::AngleAt(Seconds t_s, RotorAngleSource* source) const {
  const double w = calib_.motor_speed_radps;
  if (t_s_.empty()) {
    if (source) *source = RotorAngleSource::kUniformFallback;
    return w * t_s;
  }
  if (t_s < t_s_.front() || t_s > t_s_.back()) {
    if (source) *source = RotorAngleSource::kUniformFallback;
    const size_t i = t_s < t_s_.front() ? 0 : t_s_.size() - 1;
    return theta_rad_[i] + w * (t_s - t_s_[i]);
  }
  if (source) *source = RotorAngleSource::kEncoder;
  const auto it = std::upper_bound(t_s_.begin(), t_s_.end(), t_s);
  const size_t hi = std::min<size_t>(it - t_s_.begin(), t_s_.size() - 1);
  const size_t lo = hi == 0 ? 0 : hi - 1;
  if (hi == lo) return theta_rad_[lo];
  const double s = (t_s - t_s_[lo]) / (t_s_[hi] - t_s_[lo]);
  return theta_rad_[lo] + s * (theta_rad_[hi] - theta_rad_[lo]);
}

void RotorAngleInterpolator::DropBefore(Seconds t_s) {
  const auto it = std::lower_bound(t_s_.begin(), t_s_.end(), t_s);
  const size_t n = it - t_s_.begin();
  if (n <= 1) return;
  t_s_.erase(t_s_.begin(), t_s_.begin() + (n - 1));
  theta_rad_.erase(theta_rad_.begin(), theta_rad_.begin() + (n - 1));
}

RotaryTransform::RotaryTransform(const RigCalib& calib, const RotorAngleInterpolator& rotor)
    : rotor_(rotor),
      R_rotor_lidar_(calib.T_rotor_lidar.linear()),
      R_base_motor_(calib.T_base_motor.linear()),
      t_rotor_lidar_(calib.T_rotor_lidar.translation()),
      t_base_motor_(calib.T_base_motor.translation()) {}

void RotaryTransform::Seek(Seconds t_s) {
  const std::vector<Seconds>& ts = rotor_.sample_times();
  const std::vector<double>& th = rotor_.sample_angles();
  // AngleAt's bracketing: hi = first sample after t_s (clamped to the last), lo = hi - 1.
  size_t hi = have_ && lo_ + 2 < ts.size() && ts[lo_ + 1] <= t_s && t_s < ts[lo_ + 2]
                  ? lo_ + 2
                  : size_t(std::upper_bound(ts.begin(), ts.end(), t_s) - ts.begin());
  hi = std::min(hi, ts.size() - 1);
  lo_ = hi == 0 ? 0 : hi - 1;
  have_ = true;
  t_lo_ = ts[lo_], t_hi_ = ts[hi];
  single_ = hi == lo_;
  rate_ = single_ ? 0.0 : (th[hi] - th[lo_]) / (ts[hi] - ts[lo_]);
  theta_lo_ = th[lo_];
  cos_lo_ = std::cos(theta_lo_), sin_lo_ = std::sin(theta_lo_);
}

// T_base_lidar(theta) * p applied as T_base_motor * (RotZ(theta) * (T_rotor_lidar * p)): the fixed transforms
// stay fixed and the rotor turn is a 2D rotation, instead of composing two 4x4 poses per point.
size_t LidarToBase(const RigCalib& calib, const RotorAngleInterpolator& rotor, const LidarScan& scan,
                   std::vector<Eigen::Vector3d>* p_base) {
  p_base->resize(scan.points.size());
  RotaryTransform rotary(calib, rotor);
  size_t fallback = 0;
  for (size_t i = 0; i < scan.points.size(); ++i) {
    bool fell_back = false;
    (*p_base)[i] = rotary.Apply(scan.points[i], &fell_back);
    fallback += fell_back ? 1 : 0;
  }
  return fallback;
}

}  // namespace rotolidar
