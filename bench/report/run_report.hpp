#pragma once
// The HTML report of one run (`rotolidar demo`, `rotolidar slam`): a self-contained report.html beside the
// run's outputs (inline SVG plots, base64 PNG rasters; bench/report/html_report.hpp). Sections, by id:
//   headline     run facts, ATE / RPE / deskew error / runtime / real-time factor / scans / map points / map
//                metrics
//   trajectory   top view of the estimate (SE(3)-aligned) against the truth [scene frame, m]
//   ape          APE per pose over time                                      (truth only)
//   rpe          histogram of the translation RPE over 1 m of path           (truth only)
//   health       registration problems: stretches of scans that did not converge or were degenerate (also
//                shaded in the ape and timing plots)
//   timing       time per scan against the real-time budget, per-stage timing table and bars
//   map          top view of the map coloured by map-to-truth distance (truth) or by height (no truth)
//   coverage     covered vs missed surface samples (top view), coverage per surface class (map metrics only)
//   elements     measured vs true door / window / column sizes                (map metrics only)
//   loops        loop closure: counts and the loop edges on a top view        (loop closure on)
//   camera       the camera path per scan and tracked features on sample frames (visual.enabled)
//   config       the resolved configs of the run (collapsed)
// Sections whose data is missing are left out; a note at the top says which and why. Nothing is faked.
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "bench/report/run_evaluation.hpp"
#include "bench/run/slam_run.hpp"
#include "core/util/log.hpp"

namespace rotolidar::bench {

struct RunReportInput {
  std::string title;                                          ///< page title
  std::vector<std::pair<std::string, std::string>> run_info;  ///< first rows of the headline (scene, seed ...)
  const SlamRunResult* slam = nullptr;                        ///< required (borrowed)
  const RunEvaluation* evaluation = nullptr;                  ///< required (borrowed); may hold no truth
  /// The recording (for the camera section's sample frames); empty: none.
  std::string recording_dir;
  /// Resolved config files shown in the config section: (title, path); unreadable paths are noted.
  std::vector<std::pair<std::string, std::string>> config_files;
};

/// The report as one HTML string. slam and evaluation must be set (ROTOLIDAR_CHECK).
std::string RenderRunReport(const RunReportInput& input);

/// RenderRunReport written to `path`; the Status names the path on failure.
Status WriteRunReport(const std::string& path, const RunReportInput& input);

/// metrics.json members of a run: "slam" (scans, timings, real-time factor, map points, per-stage mean ms),
/// "health" (ScanHealthJson: registration problems),
/// and with truth "ape_translation_m", "rpe_translation_m", "deskew_error_m" (when evaluation.has_deskew:
/// points, scans, scan_stride, median, p90, p95, rmse, mean, max [m], not_deskewed, outside_truth) and "map"
/// (map_metrics.hpp ToJson). Existing members of `out` are kept.
void AddRunMetricsJson(const SlamRunResult& slam, const RunEvaluation& evaluation, nlohmann::json* out);

/// For `rotolidar slam`: evaluates the run (EvaluateRun with `options`: the trajectory against truth when the
/// recording has it; the map metrics only when options.map_metrics, as `slam --score`: they cost minutes on long
/// runs), writes <slam_dir>/report.html and <slam_dir>/metrics.json, and returns the evaluation (optional).
Status WriteSlamRunReport(const std::string& recording_dir, const std::string& slam_dir, const SlamRunResult& slam,
                          const RunEvaluationOptions& options, RunEvaluation* evaluation = nullptr);

}  // namespace rotolidar::bench
