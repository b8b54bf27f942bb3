#pragma once
// The data of the rotor calibration (docs/calibration.md): the stretch of a recording where the base stands
// still while the rotor turns, and that stretch's LiDAR points with their rotor angles.
//
// Static span: the IMU is averaged over windows of window_s; the span starts at the first sample and ends where
// a window's mean angular rate or mean specific force leaves the first window's by more than the thresholds
// (means, so that the rotor's vibration lines and the sensor noise average out; the first window's mean takes
// out the gyro bias and gravity). A margin is cut off the end.
//
// Points: the VLP-16 packets decoded with the recording's intrinsics and clock offset (as the core decodes
// them), each point's rotor angle from the encoder interpolated at its firing time (RotorAngleInterpolator, the
// input calibration's encoder zero), kept when the encoder brackets it and its range lies in [min, max]; the rotor
// speed from a +-20 ms central difference (one encoder interval's rate is dominated by the count quantisation).
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/io/recording.hpp"
#include "core/types/calib.hpp"
#include "core/types/messages.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

struct StaticSpanOptions {
  double window_s = 0.5;             ///< IMU averaging window [s] (beats of the rotor's vibration lines)
  double gyro_threshold_radps = 0.01;  ///< |mean rate - first window's| that ends the span [rad/s]
  double accel_threshold_mps2 = 0.2;  ///< |mean specific force - first window's| that ends the span [m/s^2]
  double margin_s = 0.3;             ///< cut off the end of the detected span [s]
  bool Validate(std::string* error) const;
};

/// [t_start_s, t_end_s] on the rig clock.
struct TimeSpan {
  double t_start_s = 0.0, t_end_s = 0.0;
  double length_s() const { return t_end_s - t_start_s; }
};

/// The static start of `imu` as described in the file comment. Fails when there are fewer than two windows of
/// samples or the static stretch is shorter than one window.
Status DetectStaticSpan(const std::vector<ImuSample>& imu, const StaticSpanOptions& options, TimeSpan* span);

/// "A:B" (seconds on the rig clock, A < B) into *span; errors name the text.
Status ParseTimeSpan(const std::string& text, TimeSpan* span);

/// One LiDAR return for the calibration: its position in the lidar frame and its rotor angle under the input
/// calibration (unwrapped, the encoder zero of the calib the points were loaded with).
struct RotorPoint {
  Eigen::Vector3f p_lidar = Eigen::Vector3f::Zero();  ///< [m]
  double theta_rad = 0.0;                              ///< rotor angle at the firing time [rad]
  double t_s = 0.0;                                    ///< firing time on the rig clock [s]
  double omega_radps = 0.0;  ///< rotor speed there: the encoder angle's central difference over +-20 ms [rad/s]
};

struct RotorPointOptions {
  double min_range_m = 1.0;   ///< closer returns are not used (the rig's own parts, the blind zone) [m]
  double max_range_m = 30.0;  ///< farther returns are not used (sparse, large footprint) [m]
  std::size_t max_points = 600000;  ///< evenly thinned (every n-th point) to at most this many
  bool Validate(std::string* error) const;
};

/// The points of `rec` fired inside `span`, as described in the file comment, with rotor angles under `calib`
/// (normally rec.calib). Fails naming the recording when a packet cannot be decoded or no point is left.
Status LoadRotorPoints(const Recording& rec, const RigCalib& calib, const TimeSpan& span,
                       const RotorPointOptions& options, std::vector<RotorPoint>* points);

}  // namespace rotolidar::bench
