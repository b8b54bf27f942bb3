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

// T_base_lidar(theta) * p applied as T_base_motor * (RotZ(theta) * (T_rotor_lidar * p)): the fixed transforms
// stay fixed and the rotor turn is a 2D rotation, instead of composing two 4x4 poses per point.
size_t LidarToBase(const RigCalib& calib, const RotorAngleInterpolator& rotor, const LidarScan& scan,
                   std::vector<Eigen::Vector3d>* p_base) {
  p_base->clear();
  p_base->reserve(scan.points.size());
  size_t fallback = 0;
  for (const LidarPoint& p : scan.points) {
    RotorAngleSource source;
    const double theta = rotor.AngleAt(p.t_s, &source);
    if (source == RotorAngleSource::kUniformFallback) ++fallback;
    const Eigen::Vector3d p_rotor = calib.T_rotor_lidar * Eigen::Vector3d(p.x_m, p.y_m, p.z_m);
    const double c = std::cos(theta), s = std::sin(theta);
    const Eigen::Vector3d p_turned(c * p_rotor.x() - s * p_rotor.y(), s * p_rotor.x() + c * p_rotor.y(), p_rotor.z());
    p_base->push_back(calib.T_base_motor * p_turned);
  }
  return fallback;
}

}  // namespace rotolidar
