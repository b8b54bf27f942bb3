#pragma once
// `rotolidar eval`: evo_ape / evo_rpe in C++. Reads a reference and an estimated trajectory, associates them by
// time, aligns the estimate, computes per-pose (APE) or per-pair (RPE) errors and their statistics, prints
// them like evo and optionally writes JSON. Numbers are evo's (see bench/eval/trajectory_metrics.hpp).
//
// Metrics: ape, rpe (evo's), kitti (the KITTI odometry devkit's segment errors over 100-800 m: per segment,
// translation [%] or rotation [deg/100 m]; their mean is the benchmark's t_rel / r_rel).
//
// Formats: tum (both files TUM); kitti (both KITTI, no association: pose i of one is pose i of the other, and
// the counts must match, as evo does for KITTI); euroc (reference = EuRoC ground-truth CSV, estimate = TUM,
// like `evo_ape euroc`).
#include <ostream>
#include <string>
#include <vector>

#include "bench/eval/alignment.hpp"
#include "bench/eval/kitti_odometry_error.hpp"
#include "bench/eval/statistics.hpp"
#include "bench/eval/trajectory_metrics.hpp"
#include "core/io/trajectory_io.hpp"
#include "core/types/trajectory.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

enum class EvalMetric { kApe, kRpe, kKitti };
bool ParseEvalMetric(const std::string& name, EvalMetric* out);  ///< "ape", "rpe", "kitti"
const char* EvalMetricName(EvalMetric metric);                   ///< "ape", "rpe", "kitti"

struct EvalOptions {
  std::string ref_path;                                  ///< reference trajectory file
  std::string est_path;                                  ///< estimated trajectory file
  TrajectoryFormat format = TrajectoryFormat::kTum;
  Alignment align = Alignment::kNone;
  EvalMetric metric = EvalMetric::kApe;
  PoseRelation pose_relation = PoseRelation::kTranslation;
  double delta = 1.0;                                    ///< RPE only: frames (integer) or metres
  DeltaUnit delta_unit = DeltaUnit::kFrames;             ///< RPE only
  bool all_pairs = false;                                ///< RPE only
  double max_diff_s = 0.01;                              ///< association tolerance [s] (tum, euroc)
  std::string json_path;                                 ///< empty: no JSON

  /// False with a message naming the field when a path is empty, delta <= 0 (or not integer in frames),
  /// max_diff_s < 0 / not finite, or the kitti metric is asked for a relation other than trans_part / angle_deg.
  bool Validate(std::string* error) const;
};

struct EvalResult {
  Status status;                   ///< not ok: nothing below is meaningful except what was filled before
  std::string title;               ///< e.g. "APE w.r.t. translation part (m) (with SE(3) Umeyama alignment)"
  std::string unit;                ///< "m", "deg", "rad" or ""
  size_t num_ref_poses = 0;        ///< as read
  size_t num_est_poses = 0;        ///< as read
  size_t num_associated = 0;       ///< poses compared after association
  AlignmentResult alignment;       ///< maps the estimate onto the reference
  std::vector<double> errors;      ///< per pose (APE), per pair (RPE) or per segment (kitti), in `unit`
  ErrorStatistics stats;
  KittiOdometryErrors kitti;       ///< kitti metric only: segments, per-length means, t_rel and r_rel
};

/// Runs one evaluation; `out` is filled (its status equals the returned one).
Status RunEval(const EvalOptions& options, EvalResult* out);

/// Evaluates in-memory trajectories: associate (max_diff_s), align, then metric as in `options` (paths and
/// format are ignored). Used by RunEval after reading.
EvalResult EvaluateTrajectories(const Trajectory& ref, const Trajectory& est, const EvalOptions& options,
                                bool associate = true);

/// APE translation [m] of `est` against `ref` after association (0.01 s) and `align` (demo convenience).
EvalResult ComputeApe(const Trajectory& ref, const Trajectory& est, Alignment align);

/// evo-like table: title, then one "   name\tvalue" line per statistic (max mean median min rmse sse std); the
/// kitti metric adds the devkit's per-length table and its t_rel / r_rel.
void PrintEvalStats(const EvalResult& result, std::ostream& os);

/// JSON {"title", "ref_name", "est_name", "label", "options": {...}, "alignment": {...}, "stats": {...}};
/// stats use evo's stats.json keys. Error names the path when it cannot be written.
Status WriteEvalJson(const std::string& path, const EvalOptions& options, const EvalResult& result);

}  // namespace rotolidar::bench
