#pragma once
// The rotary transform: where the lidar is on the base at any time, from the motor encoder.
//   p_base = T_base_lidar(theta(t)) * p_lidar,  T_base_lidar(theta) = T_base_motor * RotZ(theta) * T_rotor_lidar
// theta(t) is interpolated between encoder samples (the default; the seed names encoder feedback as its future
// work); the seed's uniform-rotation model theta(t) = theta0 + w * (t - t0) is the fallback when no encoder
// sample brackets t.
#include <cmath>
#include <vector>

#include "core/types/calib.hpp"
#include "core/types/messages.hpp"

namespace rotolidar {

enum class RotorAngleSource { kEncoder, kUniformFallback };

/// Unwraps and interpolates encoder readings. Samples must be fed in time order; the rotor must turn less than
/// half a revolution between consecutive samples (true for any encoder rate above 2x the rotor speed in rev/s).
class RotorAngleInterpolator {
 public:
  explicit RotorAngleInterpolator(const RigCalib& calib) : calib_(calib) {}

  /// Appends a sample; samples not newer than the last one are ignored (returns false).
  bool Add(const EncoderSample& sample);
  /// Rotor angle [rad, unwrapped] at t. Uses linear interpolation between the bracketing samples; outside the
  /// buffered span it extrapolates with the uniform-rotation model (nominal speed from calib, anchored at the
  /// nearest sample) and reports kUniformFallback in *source.
  double AngleAt(Seconds t_s, RotorAngleSource* source = nullptr) const;
  /// Drops samples older than t_s (keeps one before it for interpolation).
  void DropBefore(Seconds t_s);
  bool empty() const { return t_s_.empty(); }
  /// Time of the newest sample (-inf when empty).
  Seconds last_time_s() const { return t_s_.empty() ? -1e300 : t_s_.back(); }
  /// The buffered samples: times [s] and unwrapped angles [rad], index-aligned.
  const std::vector<Seconds>& sample_times() const { return t_s_; }
  const std::vector<double>& sample_angles() const { return theta_rad_; }

 private:
  const RigCalib& calib_;
  std::vector<Seconds> t_s_;
  std::vector<double> theta_rad_;  // unwrapped
};

/// T_base_lidar(theta(t)) * p_lidar for a stream of points, theta(t) as RotorAngleInterpolator::AngleAt, with the
/// same values up to double rounding and no trigonometry per point on the encoder path: each encoder interval's
/// start angle has its cos / sin taken once, and the interpolated remainder (< 0.1 rad) uses Taylor series.
/// The previous point's interval is tried first (firing order; any order is correct). Holds references to
/// `calib` and `rotor`, which must outlive it and not change while it is used.
class RotaryTransform {
 public:
  RotaryTransform(const RigCalib& calib, const RotorAngleInterpolator& rotor);
  /// p in the base frame at its firing time [m]; *fallback = the uniform-rotation model was used.
  Eigen::Vector3d Apply(const LidarPoint& p, bool* fallback);

 private:
  void Seek(Seconds t_s);  ///< makes [lo_, lo_ + 1] the encoder interval holding t_s (t_s inside the span)
  const RotorAngleInterpolator& rotor_;
  Eigen::Matrix3d R_rotor_lidar_, R_base_motor_;
  Eigen::Vector3d t_rotor_lidar_, t_base_motor_;
  size_t lo_ = 0;                              ///< current interval start (valid when have_ is true)
  bool have_ = false;
  bool single_ = false;                        ///< one sample only: the angle is constant
  double t_lo_ = 0, t_hi_ = 0;                 ///< the interval's times [s]
  double theta_lo_ = 0, rate_ = 0;             ///< angle at t_lo [rad] and its rate over the interval [rad/s]
  double cos_lo_ = 1, sin_lo_ = 0;
};

/// Transforms one revolution's points from the lidar frame into the base frame, each at its own time.
/// Output order matches input; returns how many points used the uniform-rotation fallback. Uses RotaryTransform.
size_t LidarToBase(const RigCalib& calib, const RotorAngleInterpolator& rotor, const LidarScan& scan,
                   std::vector<Eigen::Vector3d>* p_base);

// ---- inline so that per-point loops (Estimator::Deskew, LidarToBase) inline the transform ----

namespace rotary_detail {

/// cos and sin of a small angle a (|a| < 0.1 rad: Taylor series, truncation < 1e-17).
inline void SmallSinCos(double a, double* c, double* s) {
  const double a2 = a * a;
  *c = 1.0 - a2 * 0.5 * (1.0 - a2 * (1.0 / 12) * (1.0 - a2 * (1.0 / 30) * (1.0 - a2 * (1.0 / 56) * (1.0 - a2 * (1.0 / 90)))));
  *s = a * (1.0 - a2 * (1.0 / 6) * (1.0 - a2 * (1.0 / 20) * (1.0 - a2 * (1.0 / 42) * (1.0 - a2 * (1.0 / 72)))));
}

}  // namespace rotary_detail

inline Eigen::Vector3d RotaryTransform::Apply(const LidarPoint& p, bool* fallback) {
  const std::vector<Seconds>& ts = rotor_.sample_times();
  double c, s;
  *fallback = ts.empty() || p.t_s < ts.front() || p.t_s > ts.back();
  if (*fallback) {
    const double theta = rotor_.AngleAt(p.t_s);
    c = std::cos(theta), s = std::sin(theta);
  } else {
    // The interval [t_lo, t_hi) holds t (or t == t_hi == the last sample, where AngleAt also uses it).
    if (!have_ || p.t_s < t_lo_ || (p.t_s >= t_hi_ && !(p.t_s == t_hi_ && lo_ + 2 >= ts.size()))) Seek(p.t_s);
    const double a = (p.t_s - t_lo_) * rate_;
    if (std::abs(a) < 0.1) {
      double ca, sa;
      rotary_detail::SmallSinCos(a, &ca, &sa);
      c = cos_lo_ * ca - sin_lo_ * sa, s = sin_lo_ * ca + cos_lo_ * sa;
    } else {
      const double theta = theta_lo_ + a;
      c = std::cos(theta), s = std::sin(theta);
    }
  }
  const Eigen::Vector3d p_rotor = R_rotor_lidar_ * Eigen::Vector3d(p.x_m, p.y_m, p.z_m) + t_rotor_lidar_;
  const Eigen::Vector3d p_turned(c * p_rotor.x() - s * p_rotor.y(), s * p_rotor.x() + c * p_rotor.y(), p_rotor.z());
  return R_base_motor_ * p_turned + t_base_motor_;
}

}  // namespace rotolidar
