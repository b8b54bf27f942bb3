#pragma once
// `rotolidar demo`: the whole pipeline on the built-in default — simulate the rig in a scene, run the core on
// the recording, and measure the error against the sim's truth.
//   <out>/recording/   the simulated recording (same format as a real rig's)
//   <out>/slam/        the core's outputs (trajectory.tum/.kitti, map.ply/.pcd, scans.csv, slam_config.yaml)
//   <out>/metrics.json the headline numbers
#include <string>

#include "bench/run/eval_run.hpp"
#include "bench/run/slam_run.hpp"
#include "core/pipeline/estimator_config.hpp"
#include "sim/sim_runner.hpp"

namespace rotolidar::bench {

struct DemoOptions {
  std::string out_dir = "runs/demo";
  sim::SimConfig sim = sim::DefaultSimConfig();
  EstimatorConfig slam;
};

struct DemoResult {
  sim::SimSummary sim;
  SlamRunResult slam;
  EvalResult ape;  ///< translation APE after SE(3) Umeyama alignment, against truth/base.tum [m]
};

Status RunDemo(const DemoOptions& options, DemoResult* result);

/// Writes the headline numbers as JSON.
Status WriteDemoMetrics(const std::string& path, const DemoOptions& options, const DemoResult& result);

}  // namespace rotolidar::bench
