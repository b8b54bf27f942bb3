#pragma once
// Helpers shared by the carrier path tests (tests/sim/rig/carrier_*_test.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>

#include "sim/rig/carrier_paths.hpp"

namespace rotolidar::sim::carrier_test {

inline std::string WriteFile(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "carrier_test_" + name;
  std::ofstream(path) << text;
  return path;
}

/// Maxima over a fine time grid, comparing the analytic derivatives with finite differences of the poses.
struct Smoothness {
  double v_err = 0, a_err = 0, omega_err = 0, alpha_err = 0;  ///< analytic vs central differences
  double max_speed = 0, max_accel = 0, max_jerk = 0;          ///< jerk = central difference of the analytic a
  double max_omega = 0, max_alpha = 0, max_alpha_rate = 0;
};

inline Smoothness Measure(const BaseMotion& m, double t0, double t1, double dt) {
  Smoothness s;
  const double h = 1e-4;  // for v, a, omega, alpha checks
  for (double t = t0; t <= t1; t += dt) {
    const BaseKinematics k = m.At(t), kp = m.At(t + h), km = m.At(t - h);
    const Eigen::Vector3d p = k.T_world_base.translation();
    const Eigen::Vector3d v_fd = (kp.T_world_base.translation() - km.T_world_base.translation()) / (2 * h);
    const Eigen::Vector3d a_fd = (kp.v_world_mps - km.v_world_mps) / (2 * h);
    const Eigen::Matrix3d& R = k.T_world_base.linear();
    const Eigen::Vector3d w_fd =
        LogSO3(km.T_world_base.linear().transpose() * kp.T_world_base.linear()) / (2 * h);
    const Eigen::Vector3d alpha_fd = (kp.omega_base_radps - km.omega_base_radps) / (2 * h);
    s.v_err = std::max(s.v_err, (v_fd - k.v_world_mps).norm());
    s.a_err = std::max(s.a_err, (a_fd - k.a_world_mps2).norm());
    s.omega_err = std::max(s.omega_err, (w_fd - k.omega_base_radps).norm());
    s.alpha_err = std::max(s.alpha_err, (alpha_fd - k.alpha_base_radps2).norm());
    s.max_speed = std::max(s.max_speed, k.v_world_mps.norm());
    s.max_accel = std::max(s.max_accel, k.a_world_mps2.norm());
    s.max_jerk = std::max(s.max_jerk, (kp.a_world_mps2 - km.a_world_mps2).norm() / (2 * h));
    s.max_omega = std::max(s.max_omega, k.omega_base_radps.norm());
    s.max_alpha = std::max(s.max_alpha, k.alpha_base_radps2.norm());
    s.max_alpha_rate = std::max(s.max_alpha_rate, (kp.alpha_base_radps2 - km.alpha_base_radps2).norm() / (2 * h));
    EXPECT_TRUE(p.allFinite() && R.allFinite()) << "t " << t;
  }
  std::printf("err v %.2g a %.2g w %.2g alpha %.2g | max speed %.3g accel %.3g jerk %.3g omega %.3g alpha %.3g "
              "dalpha %.3g\n",
              s.v_err, s.a_err, s.omega_err, s.alpha_err, s.max_speed, s.max_accel, s.max_jerk, s.max_omega,
              s.max_alpha, s.max_alpha_rate);
  return s;
}

// Central differences with h = 1e-4 s are exact to h^2/6 * (next derivative): position -> v within
// 1e-8/6 * 50 m/s^3 (gait jerk) ~ 1e-7; v -> a within 1e-8/6 * 700 m/s^4 ~ 1e-6; round-off ~1e-16 * 10 m / h =
// 1e-11. Bounds 1e-5 (v, omega) and 1e-4 (a, alpha) leave room for the 2 Hz gait terms. Where the jerk (angular
// jerk) is only piecewise continuous (splines through data: it jumps at the knots), a difference straddling a
// knot adds up to h * |jump| / 2 <= h * max: pass jerk_jumps to allow that.
inline void ExpectConsistentDerivatives(const Smoothness& s, bool jerk_jumps = false) {
  const double h = 1e-4;
  EXPECT_LT(s.v_err, 1e-5);
  EXPECT_LT(s.a_err, 1e-4 + (jerk_jumps ? h * s.max_jerk : 0.0));
  EXPECT_LT(s.omega_err, 1e-5);
  EXPECT_LT(s.alpha_err, 1e-4 + (jerk_jumps ? h * s.max_alpha_rate : 0.0));
}

inline HandheldWalkConfig RoomWalk() {
  HandheldWalkConfig c;
  c.waypoints = {{0, 0, 0}, {6, 0, 3.0}, {6, 4, 0}, {0, 4, 0}};
  c.closed_loop = true;
  return c;
}

// Analytic bounds for the defaults (speed 1.2, smoothing 2 s => kernel knot spacing h = 0.5 s, max K = 1.33/s,
// max |K'| = 2.67/s^2): plan acceleration <= |dv| max K = 1.7 * 1.33 = 2.3 m/s^2 at a 90 deg corner, plan jerk
// <= 1.7 * 2.67 = 4.5 m/s^3; bounce adds A (2 pi f)^2 = 3.2 m/s^2 and A (2 pi f)^3 = 40 m/s^3, sway 0.8 and 5,
// the fading of the gait a few more. Bounds: 7 m/s^2, 70 m/s^3. Speed <= 1.2 + sway (0.02 * 2 pi = 0.13) +
// fade/turn terms (< 0.07) -> 1.4 m/s, the top of the walking envelope.

/// Angle [rad] between two poses' rotations.
inline double RotationError(const Pose3& a, const Pose3& b) { return LogSO3(a.linear().transpose() * b.linear()).norm(); }

}  // namespace rotolidar::sim::carrier_test
