#pragma once
// The motion stage of `rotolidar calibrate` (docs/calibration.md, "Motion stage"): the encoder zero and the
// LiDAR-IMU time offset, which a static stretch cannot see, from the part of the recording where the rig moves.
//
// It runs the core's estimator over the recording with the static stage's calibration and the sliding window's
// two online clock estimates switched on (window.estimate_rotor_offset, window.estimate_time_offset;
// docs/backend.md): the rotor-angle offset phi (believed rotor angle - true) and the IMU time offset td (a
// correction of calib.yaml's imu_time_offset_s). In motion the IMU's rotation and specific force must agree with
// the LiDAR's registration, which a wrong rotor angle or a shifted IMU clock breaks (a hand-eye problem the
// window solves with the trajectory). The result is the window's estimate at the last scan (it has seen all of
// the motion), with the spread of the estimates over the second half of the moving scans as a stability measure.
//
// Corrections: encoder zero' = zero + phi (the decoder subtracts the zero, so the angles lose phi), and
// imu_time_offset_s' = imu_time_offset_s + td. At constant rotor speed phi also absorbs an encoder clock offset
// (rotor speed x the offset), which is what the map needs.
#include <cstddef>
#include <string>

#include "core/pipeline/estimator.hpp"
#include "core/types/calib.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

struct MotionCalibOptions {
  double min_motion_s = 5.0;  ///< the stage needs at least this much data after the static span [s]
  /// The core's configuration (defaults, or `--slam-config`); the stage switches the window's two offsets on.
  EstimatorConfig estimator;
  /// Estimates count as settled when their spread over the second half of the motion stays below these.
  double max_spread_rad = 2e-3;  ///< rotor-angle offset [rad] (0.11 deg)
  double max_spread_s = 2e-3;    ///< IMU time offset [s]
  bool Validate(std::string* error) const;
};

struct MotionCalibResult {
  double encoder_zero_change_rad = 0.0;    ///< phi at the last scan: add to encoder.zero_offset_rad [rad]
  double imu_time_offset_change_s = 0.0;   ///< td at the last scan: add to imu_time_offset_s [s]
  double encoder_zero_spread_rad = 0.0;    ///< standard deviation (population) of phi, second half of the motion [rad]
  double imu_time_offset_spread_s = 0.0;   ///< the same for td [s]
  double t_start_s = 0.0, t_end_s = 0.0;   ///< the moving scans used (rig time) [s]
  std::size_t scans = 0;                   ///< scans after the static span with the window running
  double path_length_m = 0.0;              ///< the estimated base path over those scans [m]
  double rotation_rad = 0.0;               ///< the estimated base rotation summed over those scans [rad]
  double median_scan_ms = 0.0;             ///< the estimator's median time per scan [ms]
  bool settled = false;                    ///< both spreads within MotionCalibOptions' limits
};

/// Runs the stage over the recording in `recording_dir` with `calib` (the static stage's output) from rig time
/// `motion_start_s` (the static span's end) and writes the estimator's outputs (trajectory, map, scans.csv; bench/
/// run/slam_run.hpp) into `out_dir`. Fails naming the recording when less than min_motion_s of data follows
/// motion_start_s, when the recording has no IMU, or when the estimator fails.
Status CalibrateMotion(const std::string& recording_dir, const RigCalib& calib, double motion_start_s,
                       const MotionCalibOptions& options, const std::string& out_dir, MotionCalibResult* result);

/// calib with the result's corrections applied (the formulas in the file comment).
RigCalib ApplyMotionCorrection(const RigCalib& calib, const MotionCalibResult& result);

}  // namespace rotolidar::bench
