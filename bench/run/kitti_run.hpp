#pragma once
// `rotolidar slam --kitti DIR`: runs the core on a KITTI odometry sequence (docs/kitti.md), LiDAR-only, or
// LiDAR-inertial when the sequence has an IMU (imu.csv + calib_imu_to_velo.txt, core/io/kitti.hpp).
//
// KITTI's bins are motion-compensated clouds in the Velodyne frame of their frame, so base = velodyne: each bin
// becomes ScanPoints (KittiScanPoints: rings from the scan-line order, split by the per-point times of
// velodyne_times/ when the sequence has them, else by azimuth) fed to Estimator::ProcessDeskewedScan at the
// frame's time (no rotary transform, no deskew), or, for raw bins (KittiRunOptions::deskew), to
// Estimator::ProcessTimedScan, which deskews them with the IMU or a constant twist. With an IMU, its samples up to each frame's time are fed first and
// the calibration's T_base_imu is calib_imu_to_velo.txt's T_velo_imu (the IMU noise: RigCalib's defaults). The scan lines expected per frame: KittiScanConfig::
// expected_lines when set, else sequence_info.txt's scan_lines, else the first frame's count. The estimator's world is the Velodyne frame of the first
// frame used. Outputs in out_dir:
//   trajectory.kitti    KITTI convention: T_cam0(first)_cam0(k) = Tr * T_velo(first)_velo(k) * Tr^-1, one line per
//                       frame used (the first line is the identity)
//   trajectory.tum      the same poses with the frame times (TUM)
//   trajectory_velo.tum T_velo(first)_velo(k), the estimator's own output
//   times.txt           frame times [s], one per line
//   map.ply             the dense map, Velodyne frame of the first frame [m]
//   scans.csv           per frame: time, id, points, scan lines, registration outcome, timings
//   slam_config.yaml    the resolved estimator config
//   metrics.json        run summary; with ground truth: APE and RPE against it (rebased to the first frame used)
#include <functional>
#include <string>
#include <vector>

#include "bench/run/eval_run.hpp"
#include "bench/run/input_check.hpp"
#include "core/io/kitti.hpp"
#include "core/pipeline/estimator.hpp"

namespace rotolidar::bench {

/// The estimator defaults with KITTI's HDL-64E car data in mind: the range gate drops the car itself (< 2 m)
/// and keeps what a 64-beam sensor sees well (< 80 m). Everything else is EstimatorConfig's default, so
/// features.range_sigma_m comes from the run's calibration: sequence_info.txt's range_sigma_m, else
/// kKittiDefaultRangeSigmaM.
EstimatorConfig KittiEstimatorConfig();
/// Range noise [m] (1 sigma) of a sequence that does not state one: a real sensor's on matte surfaces (KITTI has
/// no calib.yaml; docs/features.md).
inline constexpr double kKittiDefaultRangeSigmaM = 0.01;

/// An auto / on / off option of the run (KittiRunOptions::imu, ::deskew; each says what its kAuto decides).
enum class KittiSwitch { kAuto, kOn, kOff };
bool ParseKittiSwitch(const std::string& word, KittiSwitch* value);  ///< "auto" | "on" | "off"

struct KittiRunOptions {
  KittiSequencePaths paths;          ///< the sequence folder and optional calib / times / poses files
  std::string out_dir = "runs/kitti";
  int start_frame = 0;               ///< first frame id used (bins with smaller ids are skipped)
  int max_frames = 0;                ///< at most this many frames from start_frame; 0 = all
  EstimatorConfig estimator = KittiEstimatorConfig();
  KittiScanConfig scan;
  /// Use the sequence's IMU: kAuto when it has one, kOn requires one (error without), kOff never.
  KittiSwitch imu = KittiSwitch::kAuto;
  /// Deskew each bin with its per-point times: kAuto when sequence_info.txt's deskew starts with "none" (raw
  /// bins), kOn always, kOff never (KITTI's own bins are already compensated).
  KittiSwitch deskew = KittiSwitch::kAuto;
  /// Fail before running when the frame check warns (missing or empty bins) instead of warning.
  bool strict = false;
  bool Validate(std::string* error) const;  ///< false naming the field (start_frame, max_frames, sub-configs)
};

struct KittiRunResult {
  std::vector<int> frame_ids;        ///< frames used, in order
  /// The frame check's findings (CheckKittiFrames): kitti.missing_frames, kitti.empty_frames.
  std::vector<InputWarning> input_warnings;
  Trajectory trajectory_velo;        ///< T_velo(first)_velo(k) at the frame times
  Trajectory trajectory_cam0;        ///< KITTI convention (see above), same times
  std::vector<ScanReport> scans;     ///< one per frame used
  bool imu_used = false;             ///< LiDAR-inertial (the sequence's IMU fed to the estimator)
  bool deskewed = false;             ///< bins deskewed by the estimator (ProcessTimedScan)
  size_t imu_samples_fed = 0;
  size_t frames_imu_initialized = 0; ///< frames whose pose came from the sliding window
  std::vector<size_t> scan_lines;    ///< scan lines (rings) found per frame
  int expected_lines = 0;            ///< the count every frame should have (see the top of this file)
  std::string expected_lines_source; ///< "option", the sequence_info.txt path, or "first frame"
  bool point_times = false;          ///< lines split by velodyne_times/ (else by azimuth)
  double range_sigma_m = 0.0;        ///< the features' range noise used [m]
  double rotor_deg_per_scan = 0.0;   ///< sequence_info.txt's rotor angle per frame (0: a fixed sensor) [deg]
  std::string range_sigma_source;    ///< "config", the sequence_info.txt path, or "default
  size_t frames_other_line_count = 0;  ///< frames whose line count != expected_lines
  size_t elevation_inversions = 0;     ///< summed over frames (0: every line split follows the beam order)
  size_t map_points = 0;
  double wall_time_s = 0.0;          ///< estimator time only (excludes reading bins) [s]
  double median_scan_ms = 0.0;
  bool nominal_times = false;        ///< the sequence had no times file
  bool has_ground_truth = false;     ///< a poses file was found or given (--poses: any reference trajectory)
  std::string poses_path;            ///< that file (when has_ground_truth)
  Trajectory ground_truth_cam0;      ///< GT rebased to the first frame used, frame times (when present)
  /// With ground truth (cam0 convention, no association: pose i = frame i):
  EvalResult ape;                    ///< translation [m], no alignment (both start at the identity)
  EvalResult ape_se3;                ///< translation [m], SE(3) Umeyama (status not ok when degenerate)
  EvalResult rpe_translation;        ///< consecutive frames, translation [m]
  EvalResult rpe_rotation;           ///< consecutive frames, angle [deg]
  /// With loop closure on (estimator.loop_closure.enabled): trajectory_* are loop-closed; these are the odometry's.
  bool loop_closure = false;
  graph::LoopClosureState loops;     ///< the loop closer's record after Finish
  Trajectory odometry_cam0;          ///< the odometry before loop closure, KITTI cam0 convention
  EvalResult ape_odometry, ape_se3_odometry;  ///< as ape / ape_se3, of odometry_cam0 (with ground truth)
};

/// Checks the chosen frames before a run: ids missing between the first and the last one (a gap in velodyne/, so
/// the estimator bridges a longer time), and bins with no point (a file shorter than one 16-byte point). Each
/// finding names the folder and the frame ids (the first 10). `picked` indexes sequence.frame_ids.
std::vector<InputWarning> CheckKittiFrames(const KittiSequence& sequence, const std::vector<size_t>& picked);

/// Opens the sequence, runs the estimator over the chosen frames, evaluates against the poses file when there is
/// one, and writes the outputs. Fails (naming the file) on unreadable input, no frame in range, or unwritable
/// output. `progress(fraction)` is called about every 10 % of the frames.
Status RunKitti(const KittiRunOptions& options, KittiRunResult* result,
                const std::function<void(double)>& progress = nullptr);

}  // namespace rotolidar::bench
