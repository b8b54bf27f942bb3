#pragma once
// Motion of the carrier platform ("base") in the world frame. The world frame is z up with gravity
// (0, 0, -9.81) m/s^2. BaseMotion is the interface the rest of the sim samples; today the motion is scripted
// (ScriptedBaseMotion, analytic derivatives), a later issue adds a MuJoCo-driven implementation.
#include <limits>
#include <string>

#include <Eigen/Core>

#include "core/types/geometry.hpp"
#include "core/types/time.hpp"
#include "core/types/trajectory.hpp"

namespace rotolidar::sim {

/// Standard gravity [m/s^2]; the world's gravity vector is (0, 0, -kGravity_mps2).
inline constexpr double kGravity_mps2 = 9.81;
inline Eigen::Vector3d GravityWorld() { return Eigen::Vector3d(0.0, 0.0, -kGravity_mps2); }

/// The full kinematic state of the base at one instant.
struct BaseKinematics {
  Pose3 T_world_base = Pose3::Identity();
  Eigen::Vector3d v_world_mps = Eigen::Vector3d::Zero();      ///< velocity of the base origin, world frame
  Eigen::Vector3d a_world_mps2 = Eigen::Vector3d::Zero();     ///< acceleration of the base origin, world frame
  Eigen::Vector3d omega_base_radps = Eigen::Vector3d::Zero();   ///< angular velocity of base wrt world, base frame
  Eigen::Vector3d alpha_base_radps2 = Eigen::Vector3d::Zero();  ///< d/dt of omega_base_radps (base frame)
};

/// Interface: the base's kinematics as a function of time on the rig clock. Implementations are immutable after
/// construction, so At() is thread-safe and may be called in any order.
class BaseMotion {
 public:
  virtual ~BaseMotion() = default;
  /// Kinematics at time t [s]. Defined for every t (implementations extrapolate or repeat outside Duration()).
  virtual BaseKinematics At(Seconds t) const = 0;
  /// Length of the meaningful motion [s], starting at t = 0; +infinity when unbounded.
  virtual Seconds Duration() const { return std::numeric_limits<double>::infinity(); }
};

/// A handheld-like closed loop: an ellipse plus a 3rd-harmonic shape term in x/y around a room centre, a vertical
/// bounce at the step frequency, yaw following the horizontal heading, and a small roll/pitch wobble.
///   u(t) = 2*pi*t/loop_period_s + phase0_rad
///   x = cx + rx cos(u) + d cos(3u),  y = cy + ry sin(u) - d sin(3u),  z = height + bounce sin(2*pi*f_b t)
///   yaw = atan2(vy, vx), roll = A_r sin(2*pi*f_r t), pitch = A_p sin(2*pi*f_p t + pi/2)
///   R_world_base = Rz(yaw) * Ry(pitch) * Rx(roll)
/// Every quantity is a sum of sinusoids, so the path is C-infinity and all derivatives are analytic.
struct ScriptedBaseMotionConfig {
  double center_x_m = 0.0, center_y_m = 0.0;  ///< loop centre in the world frame
  double radius_x_m = 3.0, radius_y_m = 2.2;  ///< ellipse semi-axes
  double shape_harmonic_m = 0.25;             ///< 3rd-harmonic amplitude d; needs 3d < min(rx, ry)
  double height_m = 1.2;                      ///< mean height of the base origin
  double loop_period_s = 20.0;                ///< one lap; defaults: speed within [0.46, 1.18] m/s
  double phase0_rad = 0.0;                    ///< loop phase at t = 0
  double bounce_amplitude_m = 0.02;           ///< vertical bounce amplitude
  double bounce_hz = 2.0;                     ///< step frequency
  double roll_amplitude_rad = 0.04, roll_hz = 1.0;    ///< side-to-side sway (half the step frequency)
  double pitch_amplitude_rad = 0.03, pitch_hz = 2.0;  ///< nodding at the step frequency
  double duration_s = 60.0;                   ///< reported by Duration(); the motion itself is periodic
  /// The room the loop must fit in (its x/y bounding box plus margin_m), e.g. a 10 x 8 m room.
  double room_min_x_m = -5.0, room_max_x_m = 5.0, room_min_y_m = -4.0, room_max_y_m = 4.0;
  double margin_m = 0.5;
  double min_speed_mps = 0.2, max_speed_mps = 2.0;  ///< walking-speed envelope checked by Validate

  /// False with a message naming the field when a value is non-finite, out of range, the loop leaves the room
  /// (with margin), or the speed leaves [min_speed_mps, max_speed_mps] anywhere on the loop.
  bool Validate(std::string* error) const;
  /// Lowest and highest horizontal speed over the loop [m/s] (closed-form bounds of the ellipse + harmonic).
  double MinSpeedBound() const;
  double MaxSpeedBound() const;
};

class ScriptedBaseMotion final : public BaseMotion {
 public:
  /// `config` must pass Validate (checked with ROTOLIDAR_CHECK: a programmer error otherwise).
  explicit ScriptedBaseMotion(const ScriptedBaseMotionConfig& config);
  BaseKinematics At(Seconds t) const override;
  Seconds Duration() const override { return config_.duration_s; }
  const ScriptedBaseMotionConfig& config() const { return config_; }

 private:
  ScriptedBaseMotionConfig config_;
};

/// Samples `motion` every dt_s over [t0_s, t1_s] (both ends included when they fall on the grid) as a
/// trajectory of T_world_base. Requires dt_s > 0 and t1_s >= t0_s.
Trajectory SampleTrajectory(const BaseMotion& motion, Seconds t0_s, Seconds t1_s, Seconds dt_s);

}  // namespace rotolidar::sim
