#pragma once
// Per-point deskew error against the sim's truth (only bench/ reads truth).
//
// A scan's points are fired over 0.1 s while the base moves and the rotor turns; the estimator maps each decoded
// point p_lidar_i (fired at t_i) into the base frame at the scan's start, report.t_start_s. The truth gives the
// same point's true position there:
//
//   p_true_i = T_world_base(t_start)^-1 * T_world_lidar(t_i) * p_lidar_i
//
// (truth/base.tum and truth/lidar.tum, interpolated by PoseAt, bench/eval/trajectory_lookup.hpp). The error
// is |deskewed_base_i - p_true_i|. It is frame-free (the estimator's world frame never enters: both sides are in
// the base frame at t_start) and range noise cancels (both use the same decoded p_lidar_i), so it measures the
// rotary transform (encoder interpolation, calibration) plus the motion compensation only.
#include <cstddef>
#include <string>
#include <vector>

#include "core/pipeline/estimator.hpp"
#include "core/types/trajectory.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

/// Order statistics of a list of errors [m]. All zero when count == 0.
struct ErrorStats {
  std::size_t count = 0;
  double mean_m = 0.0, median_m = 0.0, p90_m = 0.0, p95_m = 0.0, rmse_m = 0.0, max_m = 0.0;
};

/// Quantiles are the nearest-rank ones: the value at rank ceil(q * n) (1-based) of the sorted list; the median
/// of an even count is the mean of the two middle values. Takes the list by value (it is reordered).
ErrorStats SummarizeErrors(std::vector<float> errors_m);

/// The truth trajectories the metric needs (sim::TruthLog's base and lidar), sorted by time, >= 2 poses each.
struct DeskewTruth {
  Trajectory T_world_base;
  Trajectory T_world_lidar;
};

/// Reads <recording_dir>/truth/base.tum and truth/lidar.tum (the sim's truth log). Fails naming the file when
/// one is missing or unreadable or holds fewer than 2 poses.
Status LoadDeskewTruth(const std::string& recording_dir, DeskewTruth* truth);

/// One scan's errors. Points are skipped (and counted) when the estimator left them NaN (not deskewed) or when
/// t_start_s or their firing time lies outside the truth.
struct ScanDeskewErrors {
  Seconds t_start_s = 0.0;
  std::vector<float> errors_m;       ///< one per evaluated point, in report order
  std::size_t num_not_deskewed = 0;  ///< NaN in deskewed_base
  std::size_t num_outside_truth = 0;
};

/// Errors of one report. Fails (naming the scan's time) when the report holds no deskew data or when
/// deskew_source and deskewed_base differ in size (run the estimator with EstimatorConfig::keep_deskewed).
Status ScanDeskewError(const DeskewTruth& truth, const ScanReport& report, ScanDeskewErrors* out);

struct DeskewErrorResult {
  ErrorStats all;                      ///< over every evaluated point of every scan
  std::vector<ErrorStats> per_scan;    ///< one per report, in report order
  std::vector<Seconds> scan_t_start_s; ///< the reports' t_start_s
  ErrorStats scan_medians;             ///< statistics of the per-scan medians (scans with >= 1 point)
  std::size_t num_not_deskewed = 0, num_outside_truth = 0;
};

/// Accumulates scans one at a time (so a long run need not keep every scan's points).
class DeskewErrorAccumulator {
 public:
  explicit DeskewErrorAccumulator(DeskewTruth truth) : truth_(std::move(truth)) {}
  Status Add(const ScanReport& report);
  DeskewErrorResult Result() const;

 private:
  DeskewTruth truth_;
  std::vector<float> all_m_;
  DeskewErrorResult partial_;
};

/// The whole evaluation over a list of reports (DeskewErrorAccumulator over each).
Status EvaluateDeskew(const DeskewTruth& truth, const std::vector<ScanReport>& reports, DeskewErrorResult* result);

}  // namespace rotolidar::bench
