#include "sim/rig/base_motion.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/util/log.hpp"
#include "core/util/validation.hpp"

namespace rotolidar::sim {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;

/// A scalar signal and its first three time derivatives.
struct Signal {
  double f = 0, d1 = 0, d2 = 0, d3 = 0;
  Signal& operator+=(const Signal& o) {
    f += o.f, d1 += o.d1, d2 += o.d2, d3 += o.d3;
    return *this;
  }
};

/// A * sin(w t + p) with its derivatives.
Signal Sinusoid(double amplitude, double w, double phase, double t) {
  const double s = std::sin(w * t + phase), c = std::cos(w * t + phase);
  return {amplitude * s, amplitude * w * c, -amplitude * w * w * s, -amplitude * w * w * w * c};
}

/// A * cos(w t + p) with its derivatives.
Signal Cosinusoid(double amplitude, double w, double phase, double t) {
  return Sinusoid(amplitude, w, phase + 0.5 * M_PI, t);
}

/// Yaw = atan2(vy, vx) and its first two derivatives, from the horizontal velocity, acceleration and jerk.
Signal HeadingYaw(const Signal& x, const Signal& y) {
  const double s2 = x.d1 * x.d1 + y.d1 * y.d1;      // |v|^2, > 0 by Validate
  const double cross = x.d1 * y.d2 - y.d1 * x.d2;   // v x a
  const double cross_dot = x.d1 * y.d3 - y.d1 * x.d3;
  const double s2_dot = 2.0 * (x.d1 * x.d2 + y.d1 * y.d2);
  Signal yaw;
  yaw.f = std::atan2(y.d1, x.d1);
  yaw.d1 = cross / s2;
  yaw.d2 = cross_dot / s2 - cross * s2_dot / (s2 * s2);
  return yaw;
}

/// Body-frame angular velocity and acceleration of R = Rz(yaw) Ry(pitch) Rx(roll).
void EulerZyxRates(const Signal& roll, const Signal& pitch, const Signal& yaw, Eigen::Vector3d* omega,
                   Eigen::Vector3d* alpha) {
  const double sr = std::sin(roll.f), cr = std::cos(roll.f);
  const double sp = std::sin(pitch.f), cp = std::cos(pitch.f);
  const double rd = roll.d1, pd = pitch.d1, yd = yaw.d1;
  *omega << rd - yd * sp, pd * cr + yd * cp * sr, -pd * sr + yd * cp * cr;
  *alpha << roll.d2 - yaw.d2 * sp - yd * pd * cp,
      pitch.d2 * cr - pd * rd * sr + yaw.d2 * cp * sr - yd * pd * sp * sr + yd * rd * cp * cr,
      -pitch.d2 * sr - pd * rd * cr + yaw.d2 * cp * cr - yd * pd * sp * cr - yd * rd * cp * sr;
}

}  // namespace

double ScriptedBaseMotionConfig::MinSpeedBound() const {
  return kTwoPi / loop_period_s * (std::min(radius_x_m, radius_y_m) - 3.0 * shape_harmonic_m);
}

double ScriptedBaseMotionConfig::MaxSpeedBound() const {
  return kTwoPi / loop_period_s * (std::max(radius_x_m, radius_y_m) + 3.0 * shape_harmonic_m);
}

bool ScriptedBaseMotionConfig::Validate(std::string* error) const {
  const double values[] = {center_x_m, center_y_m, radius_x_m, radius_y_m, shape_harmonic_m, height_m,
                           loop_period_s, phase0_rad, bounce_amplitude_m, bounce_hz, roll_amplitude_rad, roll_hz,
                           pitch_amplitude_rad, pitch_hz, duration_s, room_min_x_m, room_max_x_m, room_min_y_m,
                           room_max_y_m, margin_m, min_speed_mps, max_speed_mps};
  for (double v : values)
    if (!std::isfinite(v)) return FailValidation(error, "a field is not finite");
  if (radius_x_m <= 0 || radius_y_m <= 0) return FailValidation(error, "radius_x_m/radius_y_m must be > 0");
  if (shape_harmonic_m < 0) return FailValidation(error, "shape_harmonic_m must be >= 0");
  if (loop_period_s <= 0) return FailValidation(error, "loop_period_s must be > 0");
  if (bounce_amplitude_m < 0 || bounce_hz < 0 || roll_hz < 0 || pitch_hz < 0)
    return FailValidation(error, "bounce_amplitude_m, bounce_hz, roll_hz, pitch_hz must be >= 0");
  if (std::abs(roll_amplitude_rad) > 0.5 || std::abs(pitch_amplitude_rad) > 0.5)
    return FailValidation(error, "roll_amplitude_rad/pitch_amplitude_rad must be within +-0.5 rad (a wobble)");
  if (duration_s <= 0) return FailValidation(error, "duration_s must be > 0");
  if (margin_m < 0) return FailValidation(error, "margin_m must be >= 0");
  const double reach_x = radius_x_m + shape_harmonic_m + margin_m;
  const double reach_y = radius_y_m + shape_harmonic_m + margin_m;
  if (center_x_m - reach_x < room_min_x_m || center_x_m + reach_x > room_max_x_m ||
      center_y_m - reach_y < room_min_y_m || center_y_m + reach_y > room_max_y_m) {
    std::ostringstream os;
    os << "loop (centre + radius + shape_harmonic_m + margin_m) leaves the room [" << room_min_x_m << ", "
       << room_max_x_m << "] x [" << room_min_y_m << ", " << room_max_y_m << "] m";
    return FailValidation(error, os.str());
  }
  if (MinSpeedBound() < min_speed_mps) {
    std::ostringstream os;
    os << "speed can drop to " << MinSpeedBound() << " m/s < min_speed_mps " << min_speed_mps
       << " (needs 3*shape_harmonic_m < min radius and a shorter loop_period_s)";
    return FailValidation(error, os.str());
  }
  if (MaxSpeedBound() > max_speed_mps) {
    std::ostringstream os;
    os << "speed can reach " << MaxSpeedBound() << " m/s > max_speed_mps " << max_speed_mps
       << " (lengthen loop_period_s)";
    return FailValidation(error, os.str());
  }
  return true;
}

ScriptedBaseMotion::ScriptedBaseMotion(const ScriptedBaseMotionConfig& config) : config_(config) {
  std::string error;
  ROTOLIDAR_CHECK(config_.Validate(&error), error);
}

BaseKinematics ScriptedBaseMotion::At(Seconds t) const {
  const auto& c = config_;
  const double w = kTwoPi / c.loop_period_s;
  Signal x = Cosinusoid(c.radius_x_m, w, c.phase0_rad, t);
  x += Cosinusoid(c.shape_harmonic_m, 3.0 * w, 3.0 * c.phase0_rad, t);
  x.f += c.center_x_m;
  Signal y = Sinusoid(c.radius_y_m, w, c.phase0_rad, t);
  y += Sinusoid(-c.shape_harmonic_m, 3.0 * w, 3.0 * c.phase0_rad, t);
  y.f += c.center_y_m;
  Signal z = Sinusoid(c.bounce_amplitude_m, kTwoPi * c.bounce_hz, 0.0, t);
  z.f += c.height_m;
  const Signal roll = Sinusoid(c.roll_amplitude_rad, kTwoPi * c.roll_hz, 0.0, t);
  const Signal pitch = Sinusoid(c.pitch_amplitude_rad, kTwoPi * c.pitch_hz, 0.5 * M_PI, t);
  const Signal yaw = HeadingYaw(x, y);

  BaseKinematics k;
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(yaw.f, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(pitch.f, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(roll.f, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  k.T_world_base.linear() = R;
  k.T_world_base.translation() << x.f, y.f, z.f;
  k.v_world_mps << x.d1, y.d1, z.d1;
  k.a_world_mps2 << x.d2, y.d2, z.d2;
  EulerZyxRates(roll, pitch, yaw, &k.omega_base_radps, &k.alpha_base_radps2);
  return k;
}

Trajectory SampleTrajectory(const BaseMotion& motion, Seconds t0_s, Seconds t1_s, Seconds dt_s) {
  ROTOLIDAR_CHECK(dt_s > 0 && t1_s >= t0_s, "dt_s " << dt_s << ", t0_s " << t0_s << ", t1_s " << t1_s);
  Trajectory out;
  const auto n = static_cast<long>(std::floor((t1_s - t0_s) / dt_s + 1e-9));
  out.reserve(static_cast<size_t>(n + 1));
  for (long i = 0; i <= n; ++i) {
    const Seconds t = t0_s + static_cast<double>(i) * dt_s;
    out.push_back({t, motion.At(t).T_world_base});
  }
  return out;
}

}  // namespace rotolidar::sim
