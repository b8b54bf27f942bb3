#include "bench/demo/demo.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "bench/report/html_report.hpp"
#include "bench/report/run_report.hpp"
#include "bench/run/progress.hpp"
#include "core/util/log.hpp"

namespace rotolidar::bench {
namespace {

Status WriteDemoReport(const DemoOptions& options, DemoResult* r) {
  RunReportInput in;
  char title[160];
  std::snprintf(title, sizeof(title), "rotolidar demo: %s, %.0f s simulated (seed %llu)", options.sim.scene.c_str(),
                r->sim.sim_duration_s, static_cast<unsigned long long>(options.sim.seed));
  in.title = title;
  in.run_info = {{"scene", options.sim.scene},
                 {"seed", std::to_string(options.sim.seed)},
                 {"output folder", options.out_dir},
                 {"simulated LiDAR packets / returns",
                  std::to_string(r->sim.lidar_packets) + " / " + std::to_string(r->sim.lidar_returns)},
                 {"sim wall time", Fmt("%.1f s", r->sim.wall_time_s)}};
  in.slam = &r->slam;
  in.evaluation = &r->evaluation;
  in.config_files = {{"sim (recording/sim_config.yaml)", options.out_dir + "/recording/sim_config.yaml"},
                     {"estimator (slam/slam_config.yaml)", options.out_dir + "/slam/slam_config.yaml"},
                     {"rig calibration (recording/calib.yaml)", options.out_dir + "/recording/calib.yaml"}};
  r->report_path = options.out_dir + "/report.html";
  return WriteRunReport(r->report_path, in);
}

}  // namespace

Status RunDemo(const DemoOptions& options, DemoResult* result) {
  const std::string recording = options.out_dir + "/recording";
  const std::string slam_dir = options.out_dir + "/slam";
  LOG_INFO("simulating " << options.sim.duration_s << " s of the rig in scene '" << options.sim.scene << "' -> "
                         << recording);
  if (Status s = sim::PrepareRecordingDir(recording, true); !s) return s;  // its own folder: never two runs mixed
  if (Status s = sim::RunSimulation(options.sim, recording, &result->sim, MakeProgressPrinter("sim")); !s) return s;
  LOG_INFO("running the SLAM core on the recording");
  // The deskew error needs every scan's deskewed points; RunSlam bounds how many it keeps (DeskewScanStride).
  EstimatorConfig slam_config = options.slam;
  slam_config.keep_deskewed = true;
  if (Status s = RunSlam(recording, slam_config, slam_dir, &result->slam, MakeProgressPrinter("slam")); !s) return s;
  LOG_INFO("evaluating against truth (trajectory, deskew error, map metrics)");
  RunEvaluationOptions evaluation = options.evaluation;
  evaluation.dynamic.voxel_m = slam_config.output_map_voxel_m;  // voxels seen counted in the dense map's voxel
  if (Status s = EvaluateRun(recording, slam_dir, result->slam, options.sim.scene, evaluation,
                             &result->evaluation);
      !s)
    return s;
  ReleaseDeskewData(&result->slam);  // scored: the points are not needed for metrics.json or the report
  if (!result->evaluation.has_truth) return Status::Error(recording + ": " + result->evaluation.truth_note);
  result->ape = result->evaluation.ape;
  if (Status s = WriteDemoMetrics(options.out_dir + "/metrics.json", options, *result); !s) return s;
  return options.report ? WriteDemoReport(options, result) : Status::Ok();
}

Status WriteDemoMetrics(const std::string& path, const DemoOptions& options, const DemoResult& r) {
  nlohmann::json j;
  j["scene"] = options.sim.scene;
  j["seed"] = options.sim.seed;
  j["sim"] = {{"duration_s", r.sim.sim_duration_s}, {"wall_time_s", r.sim.wall_time_s},
              {"lidar_packets", r.sim.lidar_packets}, {"lidar_returns", r.sim.lidar_returns},
              {"scene_triangles", r.sim.scene_triangles}};
  AddRunMetricsJson(r.slam, r.evaluation, &j);
  // Written whole to a temporary file and renamed: its presence marks a finished run (`rotolidar study` resumes
  // by it), so an interrupted write must never leave a partial metrics.json.
  const std::string tmp = path + ".tmp";
  {
    std::ofstream file(tmp);
    file << j.dump(2) << "\n";
    if (!file.flush()) return Status::Error(tmp + ": write failed");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  return ec ? Status::Error(path + ": rename failed: " + ec.message()) : Status::Ok();
}

}  // namespace rotolidar::bench
