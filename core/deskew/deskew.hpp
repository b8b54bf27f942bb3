#pragma once
// Motion compensation ("deskew") of one scan: every point, measured in the base frame at its own firing time t,
// is moved into the base frame at the scan's start time t0 (seed Sec. 3.2):
//   p_base(t0) = T_base(t0)_base(t) * p_base(t)
// The rotor's rotation comes first: RotaryTransform (core/deskew/rotary.hpp) places each point in the base frame
// at its own time with the encoder angle. What remains is the carrier's motion, given as a MotionTable:
// T_base(t0)_base(t) sampled at increasing times and interpolated in between. DeskewScan does both in one pass.
//
// Tables come from
//   - ImuMotionTable: IMU readings integrated from t0 with the state's velocity, gravity and biases (rotation
//     AND translation; the sliding window's estimates once the IMU is initialised), or with the accelerometer
//     ignored (gyro rotation + constant velocity: before the IMU is initialised);
//   - ConstantTwistTable: a constant twist (no IMU: the last two poses' relative motion).
// Pure functions on their arguments; thread-safe. Units SI, times on the rig clock.
#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "core/deskew/rotary.hpp"
#include "core/types/geometry.hpp"
#include "core/types/messages.hpp"
#include "core/types/scan_point.hpp"
#include "core/util/log.hpp"

namespace rotolidar {

/// T_base(t0)_base(t) at increasing times t_s[0] = t0 < t_s[1] < ...; sizes equal, at least one entry. Between
/// entries the pose interpolates with translation linear and rotation along the geodesic; outside
/// [t_s.front(), t_s.back()] the nearest end entry holds (MotionInterpolator).
struct MotionTable {
  std::vector<Seconds> t_s;
  std::vector<Pose3> T_start_t;
};

/// The state the IMU integration starts from, all in the imu frame at t0.
struct ImuMotionModel {
  Eigen::Vector3d v_imu_mps = Eigen::Vector3d::Zero();         ///< velocity of the imu origin at t0 [m/s]
  Eigen::Vector3d gravity_imu_mps2 = Eigen::Vector3d::Zero();  ///< gravity vector at t0 [m/s^2] (-g "down")
  Eigen::Vector3d bias_gyro_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d bias_accel_mps2 = Eigen::Vector3d::Zero();
  /// false: the accelerometer is ignored and v_imu_mps is held constant in the t0 frame (gyro rotation +
  /// constant velocity), for use before gravity and the velocity are known.
  bool use_accel = true;
};

/// Integrates `imu` (time-ordered, imu frame, raw readings) over [t0_s, t1_s] with the midpoint scheme of
/// core/imu/preintegration.hpp (each interval between samples uses the mean of its two readings, clipped to
/// [t0, t1]) and returns the base-frame table T_base(t0)_base(t) = T_base_imu T_imu(t0)_imu(t) T_base_imu^-1 at
/// t0, every sample time inside (t0, t1) and t1. Error (out untouched) when t1 < t0 or the samples do not
/// bracket [t0, t1] (first sample after t0 or last before t1).
Status ImuMotionTable(const std::vector<ImuSample>& imu, Seconds t0_s, Seconds t1_s, const ImuMotionModel& model,
                      const Pose3& T_base_imu, MotionTable* out);

/// Constant twist over [t0_s, t1_s]: T_base(t0)_base(t) = exp(s log(T_start_end)), s = (t - t0) / (t1 - t0),
/// sampled at `steps` + 1 evenly spaced times (steps >= 1; t1 > t0). Rotation and translation interpolate
/// separately (the SE(3) exp is not needed at scan-scale motions).
MotionTable ConstantTwistTable(const Pose3& T_start_end, Seconds t0_s, Seconds t1_s, int steps = 10);

/// The identity over [t0_s, t1_s] (no motion known).
MotionTable IdentityTable(Seconds t0_s, Seconds t1_s);

/// The table's pose T_base(t0)_base(t) at t, interpolated as MotionInterpolator does (the nearest end outside the
/// span). `table` must be non-empty with matching sizes (ROTOLIDAR_CHECK).
Pose3 MotionTablePose(const MotionTable& table, Seconds t_s);

/// The table's pose at t applied to points, T_base(t0)_base(t) * p, with no trigonometry per point: each
/// interval's relative rotation log w = Log(R_a^T R_b) is taken once, and R_a Exp(s w) p is applied with
/// Rodrigues' formula on the vector (Taylor series of sin(x)/x and (1 - cos x)/x^2 below 0.1 rad). The previous point's
/// interval is tried first (points come in firing order; any order is correct). Holds a reference to `table`,
/// which must outlive it. Non-finite inputs give non-finite outputs.
class MotionInterpolator {
 public:
  explicit MotionInterpolator(const MotionTable& table);  ///< ROTOLIDAR_CHECKs a non-empty, consistent table
  explicit MotionInterpolator(MotionTable&&) = delete;     ///< holds a reference: a temporary would dangle
  /// T_base(t0)_base(t) * p_base [m]; *outside = t lies outside the table's span (its nearest end was used).
  Eigen::Vector3d Apply(Seconds t, const Eigen::Vector3d& p_base, bool* outside);

 private:
  struct Segment {
    Eigen::Matrix3d R_a;        ///< rotation at the interval's start
    Eigen::Vector3d w;          ///< Log(R_a^T R_b) [rad]
    Eigen::Vector3d t_a, t_b;   ///< translations at both ends [m]
    double inv_dt;              ///< 1 / the interval's length [1/s]
  };
  const MotionTable& table_;
  std::vector<Segment> seg_;  ///< seg_[k - 1]: the interval t_s[k - 1] .. t_s[k]
  size_t k_ = 1;              ///< interval of the previous time
};

/// What DeskewScan could not do exactly: points outside the encoder's span (uniform-rotation fallback) and
/// outside the motion table's span (its nearest end used).
struct DeskewCounts {
  size_t rotor_fallback = 0;
  size_t motion_extrapolated = 0;
};

/// One revolution from the lidar frame at each point's firing time to the base frame at the scan's start:
///   (*out)[i] = ToScanPoint(scan.points[i], table(t_i) * T_base_lidar(theta(t_i)) * p_lidar_i)
/// with RotaryTransform and MotionInterpolator in one pass. *out is resized to the scan (its capacity is reused);
/// order matches the input. Non-finite inputs give non-finite outputs.
DeskewCounts DeskewScan(const RotorAngleInterpolator& rotor, const MotionTable& table, const LidarScan& scan,
                        std::vector<ScanPoint>* out);

// ---- inline so that the per-point loop of DeskewScan inlines the interpolation ----

namespace deskew_detail {

/// Where t falls in ts (sorted): 0 at or before the first time (and for a single time), ts.size() at or after
/// the last, otherwise k with ts[k-1] <= t < ts[k]. *outside: t lies before the first or after the last time.
/// The interval `hint` and the one after it are tried before a search (points come in firing order).
inline size_t Interval(const std::vector<Seconds>& ts, Seconds t, size_t hint, bool* outside) {
  *outside = false;
  if (t <= ts.front() || ts.size() == 1) {
    *outside = t < ts.front();
    return 0;
  }
  if (t >= ts.back()) {
    *outside = t > ts.back();
    return ts.size();
  }
  if (hint >= 1 && hint < ts.size() && ts[hint - 1] <= t && t < ts[hint]) return hint;
  if (hint >= 1 && hint + 1 < ts.size() && ts[hint] <= t && t < ts[hint + 1]) return hint + 1;  // the next one
  return size_t(std::upper_bound(ts.begin(), ts.end(), t) - ts.begin());
}

/// Exp(phi) * p by Rodrigues' formula on the vector: p + A phi x p + B phi x (phi x p), A = sin(x)/x,
/// B = (1 - cos x)/x^2, x = |phi|; Taylor series (truncation < 1e-17) for x < 0.1.
inline Eigen::Vector3d RotateByVector(const Eigen::Vector3d& phi, const Eigen::Vector3d& p) {
  const double x2 = phi.squaredNorm();
  double a, b;
  if (x2 < 1e-2) {  // multiplications by the reciprocals (a division per term would dominate the cost)
    a = 1.0 - x2 * (1.0 / 6) * (1.0 - x2 * (1.0 / 20) * (1.0 - x2 * (1.0 / 42) * (1.0 - x2 * (1.0 / 72))));
    b = 0.5 * (1.0 - x2 * (1.0 / 12) * (1.0 - x2 * (1.0 / 30) * (1.0 - x2 * (1.0 / 56) * (1.0 - x2 * (1.0 / 90)))));
  } else {
    const double x = std::sqrt(x2);
    a = std::sin(x) / x;
    b = (1.0 - std::cos(x)) / x2;
  }
  const Eigen::Vector3d wxp = phi.cross(p);
  return p + a * wxp + b * phi.cross(wxp);
}

}  // namespace deskew_detail

inline Eigen::Vector3d MotionInterpolator::Apply(Seconds t, const Eigen::Vector3d& p_base, bool* outside) {
  const std::vector<Seconds>& ts = table_.t_s;
  const size_t k = deskew_detail::Interval(ts, t, k_, outside);
  if (k == 0) return table_.T_start_t.front() * p_base;
  if (k == ts.size()) return table_.T_start_t.back() * p_base;
  k_ = k;
  const Segment& g = seg_[k - 1];
  const double s = (t - ts[k - 1]) * g.inv_dt;
  return g.R_a * deskew_detail::RotateByVector(s * g.w, p_base) + ((1.0 - s) * g.t_a + s * g.t_b);
}

}  // namespace rotolidar
