#pragma once
// Carrier target paths: how the rig's base is carried (docs/motion.md). Each is a BaseMotion (immutable after
// construction, At() thread-safe) giving the TARGET pose that the physics body tracks through a soft weld, so
// every path is smooth: C2 position with bounded jerk, orientation with bounded angular acceleration.
//
//   scripted_loop  an analytic loop around the origin (ScriptedBaseMotion): the demo's box-room walk
//   handheld       a person walking waypoints at hand height: smooth turns, pauses, gait bounce, sway, wobble
//   wheeled        a ground robot driving waypoints: fixed mount height, no roll/pitch, turns in place at pauses
//   car            a car following a spline through a waypoint CSV, speed limited by lateral acceleration
//   kitti          a KITTI odometry ground-truth trajectory, converted to a z-up base frame and interpolated
//
// Frames: world (z up, gravity -z); base x forward, y left, z up. Times: rig clock, the path starts at t = 0.
// Handheld and wheeled paths are at rest at their first waypoint for t <= first dwell and at their last one
// from Duration() - last dwell on; a car path is at rest at both ends; a KITTI path starts moving at t = 0 when
// the recording does (extrapolated with constant velocity outside its frames: initialise the physics with At(0)).
#include <memory>
#include <string>
#include <vector>

#include "core/util/log.hpp"
#include "sim/rig/base_motion.hpp"
#include "sim/rig/path_files.hpp"
#include "sim/rig/waypoint.hpp"

namespace YAML {
class Node;
class Emitter;
}  // namespace YAML

namespace rotolidar::sim {

enum class CarrierType { kScriptedLoop, kHandheld, kWheeled, kCar, kKitti };
/// The words of the types in YAML and on the command line: "scripted_loop", "handheld", "wheeled", "car", "kitti"
/// (core/io/yaml_fields.hpp finds it by argument-dependent lookup).
const std::vector<std::pair<const char*, CarrierType>>& EnumWords(CarrierType*);
/// The type's word ("unknown" outside the enum).
const char* CarrierTypeName(CarrierType type);
/// Inverse of CarrierTypeName; false for an unknown name.
bool CarrierTypeFromName(const std::string& name, CarrierType* type);

/// A person carrying the rig through waypoints. The walk is a piecewise-constant-velocity plan along the
/// waypoint polygon (speed_mps on every leg), smoothed by a C2 cubic-B-spline kernel of width smoothing_s:
/// corners are rounded (a 90 deg corner is cut by ~0.08 * speed * smoothing_s), starts and stops take
/// smoothing_s, and the speed never exceeds speed_mps. Heading follows each leg, turning smoothly at corners
/// (in place during pauses). Gait, faded in and out with the walking: vertical bounce at step_hz, lateral sway
/// and roll at step_hz / 2, pitch nod at step_hz. A waypoint's dwell_s is an exact rest of that length.
struct HandheldWalkConfig {
  std::vector<Waypoint2d> waypoints;  ///< world frame, >= 2; consecutive ones >= 0.05 m apart
  bool closed_loop = false;           ///< walk back to the first waypoint at the end of each lap
  int laps = 1;                       ///< laps of a closed loop (> 1 needs closed_loop)
  double height_m = 1.3;              ///< hand height of the base origin above z = 0 [m]
  double speed_mps = 1.2;             ///< walking speed on straight legs [m/s]
  double smoothing_s = 2.0;           ///< kernel width: duration of starts, stops and turns [s]
  double step_hz = 2.0;               ///< step frequency
  double bounce_amplitude_m = 0.02;   ///< vertical bounce amplitude at step_hz [m]
  double sway_amplitude_m = 0.02;     ///< lateral sway amplitude at step_hz / 2 [m]
  double roll_amplitude_rad = 0.03;   ///< roll wobble at step_hz / 2 (in phase with the sway)
  double pitch_amplitude_rad = 0.02;  ///< pitch nod at step_hz
  /// False with a message naming the field for non-finite or out-of-range values or bad waypoints.
  bool Validate(std::string* error) const;
};

/// A wheeled ground robot: the same smoothed waypoint plan as HandheldWalk without gait, at a fixed mount
/// height, roll = pitch = 0, turning in place during pauses.
struct WheeledConfig {
  std::vector<Waypoint2d> waypoints;  ///< world frame, >= 2; consecutive ones >= 0.05 m apart
  bool closed_loop = false;
  int laps = 1;
  double height_m = 0.35;     ///< mount height of the base origin [m]
  double speed_mps = 0.8;     ///< cruise speed [m/s]
  double smoothing_s = 3.0;   ///< kernel width [s]; peak acceleration <= 2.67 * |dv| / smoothing_s
  bool Validate(std::string* error) const;
};

/// A car on a natural cubic spline through the CSV points (chord-length parameter). Speed: the file's
/// speed_mps (linearly interpolated; cruise_speed_mps where absent), capped by sqrt(max_lateral_accel / curvature)
/// over a look-ahead/behind window, accelerated and braked within max_accel/max_decel, from rest to rest, then
/// smoothed by the cubic-B-spline kernel (smoothing_s). Heading along the spline tangent, no roll/pitch.
struct CarConfig {
  std::string waypoints_file;            ///< CSV x_m,y_m[,speed_mps] (path_files.hpp); or:
  /// inline waypoints (world frame, cruise speed; dwell ignored). Used when waypoints_file is empty; the sim
  /// fills them from the scene's `car` default path when both are empty.
  std::vector<Waypoint2d> waypoints;
  double height_m = 1.9;                 ///< roof-mount height of the base origin [m]
  double cruise_speed_mps = 8.0;         ///< speed where the file gives none [m/s]
  double max_lateral_accel_mps2 = 2.0;
  double max_accel_mps2 = 1.5;
  double max_decel_mps2 = 2.5;
  double smoothing_s = 2.0;              ///< kernel width of the speed profile [s]
  bool Validate(std::string* error) const;
};

/// A KITTI odometry ground-truth trajectory (cam0 poses). Base = cam0 with axes x forward (cam z), y left
/// (-cam x), z up (-cam y); world = the first base pose lifted to height_m, then placed at (start_x_m,
/// start_y_m) with yaw start_yaw_rad. Natural cubic splines in time through positions and unwrapped ZYX Euler
/// angles (vehicle attitudes stay far from pitch +-90 deg); t = 0 at the first frame. Times from times_file
/// (shifted to start at 0) or k / rate_hz. KITTI's ground truth has frame-level noise (sequence 00 at 10 Hz:
/// accelerations up to ~30 m/s^2 through every frame); smoothing_s > 0 low-passes the frame samples first.
struct KittiPathConfig {
  std::string poses_file;   ///< KITTI poses (12 floats a line)
  std::string times_file;   ///< optional times.txt; empty = uniform rate_hz
  double rate_hz = 10.0;    ///< frame rate when there is no times file
  double height_m = 1.9;    ///< height of the base origin at the first frame [m]
  /// Gaussian sigma [s] of a symmetric moving average over the frame samples (window shrinks at the ends, so
  /// the first and last frames stay exact) before interpolation; 0 = through every frame exactly.
  double smoothing_s = 0.0;
  double start_x_m = 0.0, start_y_m = 0.0, start_yaw_rad = 0.0;  ///< placement of the first frame in the world
  bool Validate(std::string* error) const;
};

/// Which carrier moves the base, with each type's parameters (only the active type's section is used).
struct CarrierConfig {
  CarrierType type = CarrierType::kScriptedLoop;
  ScriptedBaseMotionConfig scripted_loop;
  HandheldWalkConfig handheld;
  WheeledConfig wheeled;
  CarConfig car;
  KittiPathConfig kitti;
  /// Validates the active type's section (message prefixed with its name, e.g. "handheld.speed_mps ...").
  bool Validate(std::string* error) const;
};

/// True when the active carrier has no path of its own (handheld/wheeled/car without waypoints or file): the
/// sim fills it from the scene's default path for that carrier, then validates.
bool UsesSceneDefaultPath(const CarrierConfig& config);

/// Builds the active carrier's motion, loading its files (car, kitti). Errors (invalid config, file problems
/// with file:line, degenerate paths) come back as a Status; *motion is set only on success.
Status MakeCarrierMotion(const CarrierConfig& config, std::unique_ptr<BaseMotion>* motion);

/// The individual paths. Configs must Validate (ROTOLIDAR_CHECK) for the first two; the others return a
/// Status for bad data (e.g. too few points, a pose count that differs from the time count).
std::unique_ptr<BaseMotion> MakeHandheldWalk(const HandheldWalkConfig& config);
std::unique_ptr<BaseMotion> MakeWheeledPath(const WheeledConfig& config);
Status MakeCarPath(const CarConfig& config, const std::vector<CarWaypoint>& points,
                   std::unique_ptr<BaseMotion>* motion);
/// `T_cam0start_cam0k` as loaded by LoadKittiPoses; `times_s` empty (use rate_hz) or one per pose.
Status MakeKittiPath(const KittiPathConfig& config, const std::vector<Pose3>& T_cam0start_cam0k,
                     const std::vector<double>& times_s, std::unique_ptr<BaseMotion>* motion);

/// T_world_base of a KITTI pose under `config`'s conversion (what KittiPath interpolates between frames).
Pose3 KittiPoseToWorldBase(const KittiPathConfig& config, const Pose3& T_cam0start_cam0k);

/// YAML (sim/rig/carrier_yaml.cpp). Layout (every key optional; absent keys keep *config's values):
///   type: scripted_loop | handheld | wheeled | car | kitti
///   scripted_loop: {ScriptedBaseMotionConfig field names}
///   handheld: {waypoints: [[x_m, y_m], [x_m, y_m, dwell_s], ...], closed_loop, laps, height_m, speed_mps,
///              smoothing_s, step_hz, bounce_amplitude_m, sway_amplitude_m, roll_amplitude_rad, pitch_amplitude_rad}
///   wheeled: {waypoints, closed_loop, laps, height_m, speed_mps, smoothing_s}
///   car: {waypoints_file, height_m, cruise_speed_mps, max_lateral_accel_mps2, max_accel_mps2, max_decel_mps2,
///         smoothing_s}
///   kitti: {poses_file, times_file, rate_hz, height_m, smoothing_s, start_x_m, start_y_m, start_yaw_rad}
/// Relative file paths read from the node are resolved against the directory of `file`. Unknown keys, wrong
/// types and an invalid active section give an error naming file:line and the field (handheld/wheeled/car may
/// leave waypoints empty: the scene's default path fills them); *config is untouched on error. A missing node
/// changes nothing.
Status ParseCarrierConfig(const std::string& file, const YAML::Node& node, CarrierConfig* config);
/// Emits `type` and the active type's section (every field), as one mapping.
void EmitCarrierConfig(YAML::Emitter& out, const CarrierConfig& config);

}  // namespace rotolidar::sim
