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

/// One encoder interval: the rotor angle is theta_lo_rad + rate_radps * (t - t_lo_s) on [t_lo_s, t_hi_s].
struct RotorSegment {
  size_t lo = 0;                ///< index of the interval's first sample
  Seconds t_lo_s = 0.0, t_hi_s = 0.0;
  double theta_lo_rad = 0.0;    ///< unwrapped angle at t_lo_s [rad]
  double rate_radps = 0.0;      ///< angle rate over the interval [rad/s] (0 when one sample is buffered)
};

/// Unwraps and interpolates encoder readings. Samples must be fed in time order; the rotor must turn less than
/// half a revolution between consecutive samples (true for any encoder rate above 2x the rotor speed in rev/s).
/// Keeps its own copy of the calibration.
class RotorAngleInterpolator {
 public:
  static constexpr size_t kNoHint = size_t(-1);

  explicit RotorAngleInterpolator(const RigCalib& calib) : calib_(calib) {}

  /// Appends a sample; samples not newer than the last one are ignored (returns false).
  bool Add(const EncoderSample& sample);
  /// True when buffered samples bracket t (the encoder, not the fallback, gives the angle there).
  bool Covers(Seconds t_s) const { return !t_s_.empty() && t_s >= t_s_.front() && t_s <= t_s_.back(); }
  /// The interval holding t; requires Covers(t_s). Its end is the first sample after t, clamped to the last
  /// sample (so t equal to the last sample uses the last interval), and its start the sample before that end.
  /// `hint`: the start of a previous interval; the interval after it is tried before a binary search.
  RotorSegment SegmentAt(Seconds t_s, size_t hint = kNoHint) const;
  /// Rotor angle [rad, unwrapped] at t: SegmentAt's linear interpolation inside the buffered span; outside it
  /// the uniform-rotation model (nominal speed from calib, anchored at the nearest sample), reported as
  /// kUniformFallback in *source.
  double AngleAt(Seconds t_s, RotorAngleSource* source = nullptr) const;
  /// Drops samples older than t_s (keeps one before it for interpolation).
  void DropBefore(Seconds t_s);
  bool empty() const { return t_s_.empty(); }
  /// Time of the newest sample (-inf when empty).
  Seconds last_time_s() const { return t_s_.empty() ? -1e300 : t_s_.back(); }
  const RigCalib& calib() const { return calib_; }
  /// An online correction of the encoder zero [rad] (core/backend/lidar_offset_factor.hpp): subtracted from every
  /// angle this class gives (AngleAt, SegmentAt) from now on. Default 0.
  void set_angle_offset_rad(double offset_rad) { angle_offset_rad_ = offset_rad; }
  double angle_offset_rad() const { return angle_offset_rad_; }

 private:
  RigCalib calib_;
  double angle_offset_rad_ = 0.0;
  std::vector<Seconds> t_s_;
  std::vector<double> theta_rad_;  // unwrapped
};

/// T_base_lidar(theta(t)) * p_lidar for a stream of points, theta(t) as RotorAngleInterpolator::AngleAt, with the
/// same values up to double rounding and no trigonometry per point on the encoder path: each encoder interval's
/// start angle has its cos / sin taken once, and the interpolated remainder (< 0.1 rad) uses Taylor series.
/// The previous point's interval is tried first (firing order; any order is correct). Holds a reference to
/// `rotor`, which must outlive it and not change while it is used; the extrinsics come from rotor.calib().
class RotaryTransform {
 public:
  explicit RotaryTransform(const RotorAngleInterpolator& rotor);
  explicit RotaryTransform(RotorAngleInterpolator&&) = delete;  ///< a temporary would dangle
  /// p in the base frame at its firing time [m]; *fallback = the uniform-rotation model was used.
  Eigen::Vector3d Apply(const LidarPoint& p, bool* fallback);

 private:
  void Seek(Seconds t_s);  ///< makes segment_ the encoder interval holding t_s (t_s inside the span)
  const RotorAngleInterpolator& rotor_;
  Eigen::Matrix3d R_rotor_lidar_, R_base_motor_;
  Eigen::Vector3d t_rotor_lidar_, t_base_motor_;
  RotorSegment segment_;                       ///< valid when have_ is true
  bool have_ = false;
  bool last_ = false;                          ///< segment_ is the buffer's last interval
  double cos_lo_ = 1, sin_lo_ = 0;             ///< of segment_.theta_lo_rad
};

// ---- inline so that per-point loops (DeskewScan) inline the transform ----

namespace rotary_detail {

/// cos and sin of a small angle a (|a| < 0.1 rad: Taylor series, truncation < 1e-17).
inline void SmallSinCos(double a, double* c, double* s) {
  const double a2 = a * a;
  *c = 1.0 - a2 * 0.5 * (1.0 - a2 * (1.0 / 12) * (1.0 - a2 * (1.0 / 30) * (1.0 - a2 * (1.0 / 56) * (1.0 - a2 * (1.0 / 90)))));
  *s = a * (1.0 - a2 * (1.0 / 6) * (1.0 - a2 * (1.0 / 20) * (1.0 - a2 * (1.0 / 42) * (1.0 - a2 * (1.0 / 72)))));
}

}  // namespace rotary_detail

inline Eigen::Vector3d RotaryTransform::Apply(const LidarPoint& p, bool* fallback) {
  double c, s;
  *fallback = !rotor_.Covers(p.t_s);
  if (*fallback) {
    const double theta = rotor_.AngleAt(p.t_s);
    c = std::cos(theta), s = std::sin(theta);
  } else {
    // segment_ holds t on [t_lo, t_hi), or t == t_hi at the buffer's last sample (as SegmentAt brackets).
    const RotorSegment& g = segment_;
    if (!have_ || p.t_s < g.t_lo_s || (p.t_s >= g.t_hi_s && !(p.t_s == g.t_hi_s && last_))) Seek(p.t_s);
    const double a = (p.t_s - segment_.t_lo_s) * segment_.rate_radps;
    if (std::abs(a) < 0.1) {
      double ca, sa;
      rotary_detail::SmallSinCos(a, &ca, &sa);
      c = cos_lo_ * ca - sin_lo_ * sa, s = sin_lo_ * ca + cos_lo_ * sa;
    } else {
      const double theta = segment_.theta_lo_rad + a;
      c = std::cos(theta), s = std::sin(theta);
    }
  }
  const Eigen::Vector3d p_rotor = R_rotor_lidar_ * Eigen::Vector3d(p.x_m, p.y_m, p.z_m) + t_rotor_lidar_;
  const Eigen::Vector3d p_turned(c * p_rotor.x() - s * p_rotor.y(), s * p_rotor.x() + c * p_rotor.y(), p_rotor.z());
  return R_base_motor_ * p_turned + t_base_motor_;
}

}  // namespace rotolidar
