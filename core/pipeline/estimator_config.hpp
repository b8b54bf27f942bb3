#pragma once
// Configuration of the estimator (plain structs, defaults in-class, units in comments): one sub-config per
// pipeline stage (each module's own struct) plus the estimator's glue parameters. docs/estimator.md.
// YAML I/O lives at the edge: core/io/config_yaml.hpp.
#include <string>

#include "core/backend/imu_init.hpp"
#include "core/backend/sliding_window.hpp"
#include "core/features/curvature_features.hpp"
#include "core/preprocess/filters.hpp"
#include "core/registration/local_map.hpp"
#include "core/registration/scan_to_map.hpp"

namespace rotolidar {

/// The estimator's stage defaults where they differ from the modules' own (measured on the sim's lab recording,
/// docs/estimator.md): a rotary VLP-16 scan is a 30 deg fan, so registration needs many planar points and a
/// denser map than LOAM's full-revolution defaults.
/// features.range_sigma_m = kRangeSigmaFromCalib: the Estimator takes calib.yaml's lidar.range_sigma_m (the
/// sensor's noise belongs to the rig's calibration; the sim writes its caster's sigma there).
constexpr double kRangeSigmaFromCalib = -1.0;
/// planars_per_sector 20, edge_min_snr 5, range sigma from calib; planar_voxel_m 0.25 and less_flat_voxel_m 0.3
/// (one scan-side planar point per 25 cm, one map-side point per 30 cm: with neighbour reuse and a keyframe every
/// 2nd scan, ATE equal or better on lab, box room and parking, corridor 0.0049 -> 0.0055 m; parking register and
/// map stages ~20 % cheaper; docs/estimator.md).
FeatureConfig EstimatorFeatureDefaults();
LocalMapConfig EstimatorLocalMapDefaults();        ///< planar_voxel_m 0.2, max_keyframes 40
/// neighbour_reuse_m 0.05: a neighbour set found for a scan point serves the later outer iterations while the
/// point moves less than 5 cm (a quarter of the map's 0.2 m voxels). Exact reuse (0) re-searched ~2.2 times per
/// point and scan; parking register 4.4 -> 2.2 ms, ATE equal or better except the corridor's chaotic axis
/// (0.0044 -> 0.0049 m; docs/estimator.md).
ScanToMapConfig EstimatorRegistrationDefaults();
/// max_iterations 3: each scan adds one state to a window already at its optimum, so Ceres converges within a
/// few steps; 10 vs 3 changed no ATE by more than 1 mm on the lab / box-room runs and costs 1 ms per scan.
/// SPARSE_NORMAL_CHOLESKY: the window's Jacobian (~350 x 150) is block-sparse; the dense normal equations cost
/// ~1 ms per scan more (fuse 1.9 -> 0.8 ms; same lab / box-room ATE to 0.1 mm).
SlidingWindowConfig EstimatorWindowDefaults();

struct EstimatorConfig {
  double cut_azimuth_deg = 0.0;  ///< VLP-16 head azimuth where one revolution ends and the next begins [deg]

  PreprocessConfig preprocess;   ///< range gate, SOR, optional voxel (core/preprocess/filters.hpp)
  FeatureConfig features = EstimatorFeatureDefaults();  ///< curvature features (core/features/curvature_features.hpp)
  /// Feature scan-to-map with degeneracy remapping, at the module's (LOAM's) defaults but neighbour reuse: 5
  /// neighbours per match (10 before the visibility check; with it 5 measured better: lab 20 s ATE 0.029 -> 0.024
  /// m, corridor 0.060 -> 0.035 m, corridor 40 s 0.47 -> 0.13 m, box room 0.016 -> 0.020 m) and ~35 % faster.
  ScanToMapConfig registration = EstimatorRegistrationDefaults();
  LocalMapConfig local_map = EstimatorLocalMapDefaults();  ///< keyframe feature map (registration target)
  /// A rotary LiDAR sees new directions every scan even when the carrier stands still, so besides the local
  /// map's distance/angle rule a scan becomes a keyframe at least every this many scans. 2: the rotor turns
  /// 15 deg per scan and the VLP-16's fan is 30 deg wide, so every other band still covers the sphere; the
  /// window of 40 keyframes then spans 8 s (2+ revolutions). Measured against 1 (docs/estimator.md): ATE equal
  /// or better on lab, corridor, box room and parking (seeds 1, 2), the map stage about half.
  int keyframe_every_scans = 2;
  /// Every scan is a keyframe until the local map holds this many: a young map needs each band (24 = one rotor
  /// revolution at 2.6 rad/s). Without it the box room's moving start drifted 0.017 -> 0.05 m. 0: off.
  int initial_keyframes = 24;
  /// Before IMU initialisation, hold the pose while the IMU has been still since the start (ImuIsStill with the
  /// imu_init thresholds over the last static_window_s): the first bands then form the map (docs/estimator.md).
  bool hold_static_start = true;
  /// LiDAR-inertial sliding window (its gravity is set at IMU initialisation)
  SlidingWindowConfig window = EstimatorWindowDefaults();
  ImuInitConfig imu_init;        ///< static / moving IMU initialisation

  /// Use the IMU when samples are fed (false: LiDAR-only with gyro-free constant-velocity deskew; an ablation).
  bool use_imu = true;
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

  /// Keep each scan's decoded points and their deskewed positions in the ScanReport (deskew evaluation; memory
  /// grows with the run: ~30 k points x 44 B per scan).
  bool keep_deskewed = false;

  bool Validate(std::string* error) const;  ///< false with the offending field named in *error
};

}  // namespace rotolidar
