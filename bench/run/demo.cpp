#include "bench/run/demo.hpp"

#include <fstream>

#include <nlohmann/json.hpp>

#include "bench/run/progress.hpp"
#include "bench/run/truth_eval.hpp"

namespace rotolidar::bench {

Status RunDemo(const DemoOptions& options, DemoResult* result) {
  const std::string recording = options.out_dir + "/recording";
  LOG_INFO("simulating " << options.sim.duration_s << " s of the rig in scene '" << options.sim.scene << "' -> "
                         << recording);
  if (Status s = sim::RunSimulation(options.sim, recording, &result->sim, MakeProgressPrinter("sim")); !s) return s;
  LOG_INFO("running the SLAM core on the recording");
  if (Status s = RunSlam(recording, options.slam, options.out_dir + "/slam", &result->slam, MakeProgressPrinter("slam"));
      !s)
    return s;
  if (Status s = EvaluateAgainstTruth(recording, result->slam.trajectory, &result->ape); !s) return s;
  return WriteDemoMetrics(options.out_dir + "/metrics.json", options, *result);
}

Status WriteDemoMetrics(const std::string& path, const DemoOptions& options, const DemoResult& r) {
  nlohmann::json j;
  j["scene"] = options.sim.scene;
  j["seed"] = options.sim.seed;
  j["sim"] = {{"duration_s", r.sim.sim_duration_s}, {"wall_time_s", r.sim.wall_time_s},
              {"lidar_packets", r.sim.lidar_packets}, {"lidar_returns", r.sim.lidar_returns},
              {"scene_triangles", r.sim.scene_triangles}};
  j["slam"] = {{"scans", r.slam.scans.size()}, {"median_scan_ms", r.slam.median_scan_ms},
               {"wall_time_s", r.slam.wall_time_s}, {"data_duration_s", r.slam.data_duration_s},
               {"realtime_factor", r.slam.wall_time_s > 0 ? r.slam.data_duration_s / r.slam.wall_time_s : 0.0},
               {"map_points", r.slam.map_points}};
  const ErrorStatistics& s = r.ape.stats;
  j["ape_translation_m"] = {{"alignment", "se3"}, {"poses", r.ape.num_associated}, {"rmse", s.rmse},
                            {"mean", s.mean}, {"median", s.median}, {"std", s.std}, {"min", s.min}, {"max", s.max}};
  std::ofstream file(path);
  file << j.dump(2) << "\n";
  return file ? Status::Ok() : Status::Error(path + ": write failed");
}

}  // namespace rotolidar::bench
