#pragma once
// Runs the core estimator over a recording folder and writes its outputs:
//   trajectory.tum, trajectory.kitti (+ trajectory_times.txt)   T_world_base at each scan start
//   map.ply, map.pcd                                            the dense map [world, m]
//   scans.csv          per scan: stage timings [ms], feature counts, registration, degeneracy (eigenvalues, axes)
//   slam_config.yaml                                            the resolved estimator config
// Each file is written under a temporary name and renamed (a reader never sees half of one); a run first removes
// the outputs of an earlier run in the same folder. `rotolidar slam` writes metrics.json last: its presence marks
// a finished run, and its "complete" says whether the run saw all of its data.
// With loop closure on, also trajectory_odometry.tum, loops.csv, loop_candidates.csv, map_corrected.ply and, when
// asked (SlamRunOptions::save_keyframes), the keyframe database in keyframes/ (bench/run/keyframe_db.hpp).
//
// With EstimatorConfig::keep_deskewed the reports also keep each scan's decoded points and their deskewed
// positions (the deskew error's input, bench/metrics/deskew_error.hpp): ~30 k points x 44 B per scan, so a 20 s
// run holds ~5.7 M points (~250 MB), which is fine. Longer runs keep them for every k-th scan only
// (DeskewScanStride), so the kept points stay at about 20 s worth whatever the run's length.
#include <atomic>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "bench/run/input_check.hpp"
#include "core/pipeline/estimator.hpp"
#include "core/types/trajectory.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

/// A player hands camera frames to the estimator this far ahead of the LiDAR packets of the same time [s], as a
/// live camera's frames arrive between the packets: the tracker's thread then works while the estimator handles
/// the scan. More than VisualConfig::max_image_offset_s (0.05 s), so every frame a state can choose is in when
/// the state is fused (core/pipeline/visual_frontend.hpp).
inline constexpr double kCameraFrameLeadS = 0.1;

struct SlamRunResult {
  Trajectory trajectory;            ///< T_world_base (loop-closed when loop closure is on)
  Trajectory odometry_trajectory;   ///< T_world_base as the odometry gave it (before loop closure)
  graph::LoopClosureState loops;    ///< empty without loop closure
  /// The loop closer's keyframe database (SlamRunOptions::keep_keyframes; ~24 B per stored point), else empty.
  std::vector<graph::KeyframeCloud> loop_keyframes;
  size_t loop_snapshots = 0;  ///< snapshots written (SlamRunOptions::loop_snapshots)
  std::vector<ScanReport> scans;
  size_t map_points = 0;
  size_t bad_packets = 0;
  PacketOrderCounts packet_order;  ///< data packets put back in order or dropped (Estimator::packet_order_counts)
  std::vector<InputWarning> input_warnings;  ///< what CheckRecording found in the recording (bench/run/input_check.hpp)
  double data_duration_s = 0.0;     ///< span of the LiDAR data [s]
  double wall_time_s = 0.0;         ///< estimator time only (excludes loading) [s]
  double median_scan_ms = 0.0;      ///< median Process time per scan [ms]
  /// SlamRunOptions::stop was set: the outputs cover the data fed until then (data_fed_s of LiDAR data).
  bool stopped = false;
  double data_fed_s = 0.0;
  /// 0: no scan kept its deskew data (keep_deskewed off, or ReleaseDeskewData). k >= 1: scans[i] with
  /// i % k == 0 hold deskew_source / deskewed_base, the others hold none.
  size_t deskew_scan_stride = 0;
};

/// Seconds of LiDAR data whose every scan keeps its deskew data; longer runs keep every k-th scan.
inline constexpr double kDeskewKeepAllSpanS = 20.0;

/// The deterministic subsampling rule for a run spanning `data_span_s` of LiDAR data:
/// k = max(1, ceil(data_span_s / kDeskewKeepAllSpanS)); the scans with index 0, k, 2k, ... keep their points.
size_t DeskewScanStride(double data_span_s);

/// Frees every scan's deskew data (once it has been evaluated) and sets deskew_scan_stride to 0.
void ReleaseDeskewData(SlamRunResult* result);

struct SlamRunOptions {
  std::function<void(double)> progress;  ///< called with the fraction done, about every 10 % of the data
  bool save_keyframes = false;  ///< loop closure on: write the keyframe database into <out_dir>/keyframes/
  bool keep_keyframes = false;  ///< loop closure on: fill SlamRunResult::loop_keyframes
  /// Loop closure on: after each pose-graph correction write the corrected map and trajectory so far into
  /// <out_dir>/loop_snapshots/ (bench/run/loop_outputs.hpp).
  bool loop_snapshots = false;
  /// Polled before each packet: when set, the run stops feeding, finishes what it has and writes its outputs
  /// (SlamRunResult::stopped; metrics.json says complete: false). A signal handler sets it.
  const std::atomic<bool>* stop = nullptr;
  /// A finding of CheckRecording (a degraded input) fails the run instead of being a warning.
  bool strict = false;
  /// Used instead of the recording's calib.yaml when set (e.g. `rotolidar calibrate`'s corrected one); not owned.
  const RigCalib* calib = nullptr;
};

Status RunSlam(const std::string& recording_dir, const EstimatorConfig& config, const std::string& out_dir,
               SlamRunResult* result, const SlamRunOptions& options);
/// Writes the outputs listed at the top of this file for `estimator` after its last scan (RunSlam's last step;
/// `rotolidar live` calls it at the end of a session). Fails naming the file that could not be written.
Status WriteSlamOutputs(const std::string& out_dir, const Estimator& estimator, const SlamRunResult& result);
/// Removes the outputs an earlier run wrote into out_dir (the files above, keyframes/, loop_snapshots/, and
/// metrics.json and report.html), so that a folder never mixes two runs; other files are left alone.
Status ClearSlamOutputs(const std::string& out_dir);
/// RunSlam with `progress` only.
Status RunSlam(const std::string& recording_dir, const EstimatorConfig& config, const std::string& out_dir,
               SlamRunResult* result, const std::function<void(double)>& progress = nullptr);

}  // namespace rotolidar::bench
