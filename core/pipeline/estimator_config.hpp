#pragma once
// Configuration of the estimator (plain structs, defaults in-class, units in comments): one sub-config per
// pipeline stage (each module's own struct) plus the estimator's glue parameters. docs/estimator.md.
// YAML I/O lives at the edge: core/pipeline/estimator_config_yaml.hpp.
#include <string>

#include "core/backend/imu_init.hpp"
#include "core/backend/sliding_window.hpp"
#include "core/features/curvature_features.hpp"
#include "core/graph/loop_closer.hpp"
#include "core/pipeline/free_space.hpp"
#include "core/pipeline/visual_frontend.hpp"
#include "core/preprocess/filters.hpp"
#include "core/registration/local_map.hpp"
#include "core/registration/scan_to_map.hpp"
#include "core/wire/packet_orderer.hpp"
#include "core/types/calib.hpp"

namespace rotolidar {

/// Values the Estimator derives from the rig's calibration (calib.yaml) when a config leaves them at these
/// markers (the defaults): the sensor's noise and the rotor's speed belong to the rig, not to a config file.
/// features.range_sigma_m: calib.yaml's lidar.range_sigma_m (the sim writes its caster's sigma there).
constexpr double kRangeSigmaFromCalib = -1.0;
/// keyframe_every_scans / initial_keyframes: RotaryKeyframePolicy(calib, local_map).
constexpr int kDeriveFromCalib = -1;

/// The keyframe policy of a rotary rig, from its calibration. The rotor turns a = |motor_speed_radps| * 60 / rpm
/// [rad] per scan and the VLP-16's fan is 30 deg wide (elevations -15..+15 deg), so
///   every_scans       = max(1, floor(30 deg / a)): every other band still overlaps its neighbours' fans;
///   initial_keyframes = min(floor(2 pi / a), max_keyframes): a young map takes every scan for one revolution.
/// A rotor at rest (a < 1e-6 rad) forces neither (both 0: the local map's distance/angle rule alone decides).
/// The seed's 2.6 rad/s at 600 rpm: a = 14.9 deg, every 2nd scan after 24 (why: docs/estimator.md,
/// 'Keyframe policy').
struct KeyframePolicy {
  int every_scans = 1;
  int initial_keyframes = 0;
};
KeyframePolicy RotaryKeyframePolicy(const RigCalib& calib, const LocalMapConfig& local_map);

struct EstimatorConfig {
  double cut_azimuth_deg = 0.0;  ///< VLP-16 head azimuth where one revolution ends and the next begins [deg]
  /// Data packets are put back into timestamp order before decoding; duplicates, late and wild-stamped packets
  /// are dropped and counted (core/wire/packet_orderer.hpp).
  PacketOrderConfig packet_order;

  PreprocessConfig preprocess;   ///< range gate, SOR, optional voxel (core/preprocess/filters.hpp)
  /// Curvature features (core/features/curvature_features.hpp); the noise gate's sigma from calib.yaml.
  FeatureConfig features = FeaturesWithRangeSigmaFromCalib();
  ScanToMapConfig registration;  ///< feature scan-to-map with degeneracy handling (core/registration)
  LocalMapConfig local_map;      ///< keyframe feature map (registration target)
  /// A rotary LiDAR sees new directions every scan even when the carrier stands still, so besides the local
  /// map's distance/angle rule a scan becomes a keyframe at least every this many scans (0: never forced).
  /// Default: derived from the calibration (RotaryKeyframePolicy).
  int keyframe_every_scans = kDeriveFromCalib;
  /// Every scan is a keyframe until the local map holds this many: a young map needs each band (why:
  /// docs/estimator.md, 'Keyframe policy'). 0: off. Default: derived (RotaryKeyframePolicy).
  int initial_keyframes = kDeriveFromCalib;
  /// Before IMU initialisation, hold the pose while the IMU has been still since the start (ImuIsStill with the
  /// imu_init thresholds over the last static_window_s): the first bands then form the map (docs/estimator.md).
  bool hold_static_start = true;
  /// LiDAR-inertial sliding window (its gravity is set at IMU initialisation)
  SlidingWindowConfig window;
  ImuInitConfig imu_init;        ///< static / moving IMU initialisation

  /// Use the IMU when samples are fed (false: LiDAR-only with gyro-free constant-velocity deskew; an ablation).
  bool use_imu = true;
  /// With use_imu false the registration's guess along a weak direction is the constant-twist extrapolation, which
  /// no sensor holds: this replaces the weak-direction gate (registration.degeneracy.weak_gate_m) [m]. Wide enough
  /// that only a broken solve is refused (why: docs/registration.md, "The gate without an IMU"). Finite, > 0.
  double lidar_only_weak_gate_m = 3.0;
  /// With use_imu false the guess's translation velocity is the mean over the measured poses of this last span [s]
  /// (rotation: the last two scans'); 0: the last two scans' twist. >= 0. Why 0.9 s: docs/registration.md, "A
  /// LiDAR-only motion model for a rotary rig".
  double lidar_only_velocity_window_s = 0.9;
  /// With use_imu false this replaces registration.max_correspondence_rebuilds: a turn's onset leaves the
  /// constant-velocity guess degrees off, which takes more rebuilds than an IMU-propagated guess. >= 1.
  int lidar_only_max_correspondence_rebuilds = 30;
  /// Per-point residual sigma that turns the registration Hessian into the LiDAR factor's information [m]
  /// (InformationFromRegistration). It absorbs the correlation between points: larger = trust the scan less.
  double lidar_point_sigma_m = 0.05;
  /// Scans of LiDAR-only odometry collected before the IMU is initialised (the moving start needs
  /// imu_init.moving_min_poses of them; the static start uses the IMU's first imu_init.static_window_s).
  int imu_init_scans = 10;
  /// A scan whose registration did not converge still gives a LiDAR factor, with information scaled by this
  /// (0 = IMU-only for that scan).
  double unconverged_information_scale = 0.0;

  // Dense output map (the deskewed points, world frame)
  double output_map_voxel_m = 0.05;  ///< [m]
  int output_map_points_per_voxel = 1;
  double output_map_max_range_m = 40.0;  ///< points farther from the lidar are not added to the output map [m]
  /// Moving objects out of the maps: keyframe features and dense-map points that other scans saw through
  /// (core/pipeline/free_space.hpp). The dense map then lags delay_s behind the latest scan.
  FreeSpaceConfig free_space;
  /// Two-stage loop closure and pose graph beside the odometry (core/graph/loop_closer.hpp); off by default.
  graph::LoopClosureConfig loop_closure;
  /// The camera in the sliding window (core/pipeline/visual_frontend.hpp): tracked features as inverse-depth
  /// landmarks with reprojection factors, depths from the LiDAR. Off by default (docs/visual.md).
  VisualConfig visual;

  /// Keep each scan's decoded points and their deskewed positions in the ScanReport (deskew evaluation; memory
  /// grows with the run: ~30 k points x 44 B per scan).
  bool keep_deskewed = false;

  bool Validate(std::string* error) const;  ///< false with the offending field named in *error

 private:
  static FeatureConfig FeaturesWithRangeSigmaFromCalib() {
    FeatureConfig c;
    c.range_sigma_m = kRangeSigmaFromCalib;
    return c;
  }
};

/// The config with every derived value resolved from the calibration (what the Estimator runs with and what a
/// run writes as its resolved slam_config.yaml). With the camera fused (visual.enabled), the registration's
/// weak-direction gate becomes visual.registration_weak_gate_m.
EstimatorConfig ResolveFromCalib(const EstimatorConfig& config, const RigCalib& calib);

}  // namespace rotolidar
