#pragma once
// `rotolidar demo`: the whole pipeline on the built-in default — simulate the rig in a scene, run the core on
// the recording, and measure the errors against the sim's truth.
//   <out>/recording/    the simulated recording (same format as a real rig's; its sim_config.yaml is the
//                       resolved sim config of the run)
//   <out>/slam/         the core's outputs (trajectory.tum/.kitti, map.ply/.pcd, scans.csv, slam_config.yaml)
//   <out>/metrics.json  the headline numbers: sim, slam (timings), APE, RPE, deskew error ("deskew_error_m"),
//                       map metrics ("map")
//   <out>/report.html   the self-contained HTML report (bench/report/run_report.hpp)
#include <string>

#include "bench/report/run_evaluation.hpp"
#include "bench/run/eval_run.hpp"
#include "bench/run/slam_run.hpp"
#include "core/pipeline/estimator_config.hpp"
#include "sim/sim_runner.hpp"

namespace rotolidar::bench {

struct DemoOptions {
  std::string out_dir = "runs/demo";
  sim::SimConfig sim = sim::PresetSimConfig(sim::Realism::kTypical);
  EstimatorConfig slam;
  RunEvaluationOptions evaluation;  ///< RPE delta, map metrics (coverage distance, completeness ...)
  bool report = true;               ///< write report.html
};

struct DemoResult {
  sim::SimSummary sim;
  SlamRunResult slam;
  EvalResult ape;             ///< translation APE after SE(3) Umeyama alignment, against truth/base.tum [m]
  RunEvaluation evaluation;   ///< APE (same as `ape`), RPE, the map in the scene frame and its metrics
  std::string report_path;    ///< <out>/report.html when written
};

/// Simulates, runs SLAM (with EstimatorConfig::keep_deskewed forced on, so the deskew error can be scored),
/// evaluates (EvaluateRun with the sim's scene), writes metrics.json and report.html.
/// Progress lines go to stderr for the long stages. Fails naming the stage's file or field.
Status RunDemo(const DemoOptions& options, DemoResult* result);

/// Writes the headline numbers as JSON (sim facts plus AddRunMetricsJson's members).
Status WriteDemoMetrics(const std::string& path, const DemoOptions& options, const DemoResult& result);

}  // namespace rotolidar::bench
