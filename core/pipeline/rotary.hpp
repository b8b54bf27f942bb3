#pragma once
// The rotary transform: where the lidar is on the base at any time, from the motor encoder.
//   p_base = T_base_lidar(theta(t)) * p_lidar,  T_base_lidar(theta) = T_base_motor * RotZ(theta) * T_rotor_lidar
// theta(t) is interpolated between encoder samples (the default; the seed names encoder feedback as its future
// work); the seed's uniform-rotation model theta(t) = theta0 + w * (t - t0) is the fallback when no encoder
// sample brackets t.
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

 private:
  const RigCalib& calib_;
  std::vector<Seconds> t_s_;
  std::vector<double> theta_rad_;  // unwrapped
};

/// Transforms one revolution's points from the lidar frame into the base frame, each at its own time.
/// Output order matches input; returns how many points used the uniform-rotation fallback.
size_t LidarToBase(const RigCalib& calib, const RotorAngleInterpolator& rotor, const LidarScan& scan,
                   std::vector<Eigen::Vector3d>* p_base);

}  // namespace rotolidar
