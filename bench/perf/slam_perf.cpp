// `rotolidar bench slam`: SLAM core speed and accuracy on a simulated recording (contract in slam_perf.hpp).
#include "bench/perf/slam_perf.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>

#include <nlohmann/json.hpp>

#include "bench/perf/perf_util.hpp"
#include "bench/run/slam_run.hpp"
#include "bench/run/truth_eval.hpp"
#include "core/io/recording.hpp"
#include "core/pipeline/estimator.hpp"
#include "sim/sim_runner.hpp"

namespace rotolidar::bench {
namespace {

double WallS() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

StageTime Stage(std::vector<double> ms) {
  StageTime s;
  if (ms.empty()) return s;
  s.median_ms = PerfMedian(ms);
  std::sort(ms.begin(), ms.end());
  const std::size_t rank = static_cast<std::size_t>(std::ceil(0.9 * static_cast<double>(ms.size())));
  s.p90_ms = ms[std::clamp<std::size_t>(rank, 1, ms.size()) - 1];
  return s;
}

/// Everything one estimator run produced that the bench keeps (the reports without their points).
struct RunOutput {
  std::vector<ScanTimings> timings;
  std::vector<std::size_t> points;
  Trajectory trajectory;
  double cpu_s = 0.0, wall_s = 0.0, data_s = 0.0;
};

/// Plays the recording into a fresh estimator in time order (packets by capture time, sensors up to each
/// packet), timing only the estimator's calls. With `deskew`, each report is scored and its points dropped.
Status RunOnce(const Recording& rec, const EstimatorConfig& config, DeskewErrorAccumulator* deskew, RunOutput* out) {
  Estimator estimator(rec.calib, config);
  double cpu = 0.0, wall = 0.0;
  Status status = Status::Ok();
  Seconds first_start = 0.0, last_end = 0.0;
  auto take = [&](std::vector<ScanReport> reports) {
    for (ScanReport& r : reports) {
      if (out->timings.empty()) first_start = r.t_start_s;
      last_end = r.t_end_s;
      out->timings.push_back(r.timings);
      out->points.push_back(r.num_points);
      if (deskew && status) status = deskew->Add(r);
    }
  };
  std::size_t i_imu = 0, i_enc = 0, i_cam = 0;
  for (const LidarPacket& packet : rec.lidar_packets) {
    const double c0 = ProcessCpuS(), w0 = WallS();
    while (i_enc < rec.encoder.size() && rec.encoder[i_enc].t_s <= packet.t_capture_s)
      estimator.Feed(rec.encoder[i_enc++]);
    while (i_imu < rec.imu.size() && rec.imu[i_imu].t_s <= packet.t_capture_s) estimator.Feed(rec.imu[i_imu++]);
    while (i_cam < rec.camera.size() && rec.camera[i_cam].t_s <= packet.t_capture_s + kCameraFrameLeadS)
      estimator.Feed(rec.camera[i_cam++]);  // decoded only when kept (without visual.enabled: none)
    (void)estimator.Feed(packet);  // a malformed packet is skipped and counted (Estimator::bad_packets)
    std::vector<ScanReport> reports = estimator.Process();
    cpu += ProcessCpuS() - c0, wall += WallS() - w0;
    take(std::move(reports));
  }
  const double c0 = ProcessCpuS(), w0 = WallS();
  while (i_enc < rec.encoder.size()) estimator.Feed(rec.encoder[i_enc++]);
  while (i_imu < rec.imu.size()) estimator.Feed(rec.imu[i_imu++]);
  std::vector<ScanReport> reports = estimator.Finish();
  cpu += ProcessCpuS() - c0, wall += WallS() - w0;
  take(std::move(reports));
  out->cpu_s = cpu, out->wall_s = wall, out->data_s = last_end - first_start;
  out->trajectory = estimator.trajectory();
  return status;
}

Status Simulate(const SlamBenchOptions& o) {
  sim::SimConfig config = sim::DefaultSimConfig();
  config.scene = o.scene;
  config.duration_s = o.duration_s;
  config.seed = o.seed;
  config.camera.enabled = o.camera;  // the LiDAR-inertial core reads no images: rendering them would only cost time
  if (o.carrier == "handheld") config.carrier.type = sim::CarrierType::kHandheld;  // the scene's default walk
  else config.carrier.type = sim::CarrierType::kScriptedLoop;
  sim::SimSummary summary;
  return sim::RunSimulation(config, o.recording_dir, &summary);
}

}  // namespace

bool SlamBenchOptions::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) { return (error ? *error = "bench slam: " + m : m), false; };
  if (!(duration_s > 0.0 && duration_s <= 3600.0)) return fail("--duration must be in (0, 3600]");
  if (carrier != "handheld" && carrier != "scripted_loop") return fail("--carrier: handheld or scripted_loop");
  if (repetitions < 1 || repetitions > 100) return fail("--reps must be in 1..100");
  if (threads < 1 || threads > 256) return fail("--threads must be in 1..256");
  if (recording_dir.empty()) return fail("--recording must not be empty");
  return true;
}

Status RunSlamBench(const SlamBenchOptions& o, SlamBenchResult* result) {
  std::string why;
  if (!o.Validate(&why)) return Status::Error(why);
  if (Status s = Simulate(o); !s) return Status::Error("bench slam: simulation: " + s.message);
  Recording rec;
  if (Status s = LoadRecording(o.recording_dir, &rec); !s) return s;
  DeskewTruth truth;
  if (Status s = LoadDeskewTruth(o.recording_dir, &truth); !s) return s;
  EstimatorConfig config;
  config.keep_deskewed = true;
  config.features.threads = o.threads;
  config.registration.num_threads = o.threads;
  config.window.num_threads = o.threads;
  config.visual.enabled = o.camera;
  if (!config.Validate(&why)) return Status::Error("bench slam: estimator config: " + why);

  *result = SlamBenchResult();
  DeskewErrorAccumulator deskew(std::move(truth));
  std::vector<double> cpu, wall;
  std::vector<double> total, desk, pre, feat, reg, fuse, map;
  std::vector<double> points;
  for (int rep = 0; rep < o.repetitions; ++rep) {
    config.keep_deskewed = rep == 0;
    RunOutput run;
    if (Status s = RunOnce(rec, config, rep == 0 ? &deskew : nullptr, &run); !s) return s;
    if (run.timings.empty()) return Status::Error("bench slam: the estimator produced no scan");
    const bool timed = rep > 0 || o.repetitions == 1;  // the scoring run only times when it is the only one
    if (timed) cpu.push_back(run.cpu_s), wall.push_back(run.wall_s);
    for (const ScanTimings& t : timed ? run.timings : std::vector<ScanTimings>()) {
      total.push_back(t.total_ms), desk.push_back(t.deskew_ms), pre.push_back(t.preprocess_ms);
      feat.push_back(t.features_ms), reg.push_back(t.register_ms), fuse.push_back(t.fuse_ms), map.push_back(t.map_ms);
    }
    if (rep > 0) continue;
    result->scans = run.timings.size();
    result->data_s = run.data_s;
    for (const std::size_t n : run.points) points.push_back(static_cast<double>(n));
    EvalResult ate;
    if (Status s = EvaluateAgainstTruth(o.recording_dir, run.trajectory, &ate); !s) return s;
    result->ate_rmse_m = ate.stats.rmse, result->ate_max_m = ate.stats.max, result->ate_poses = ate.stats.count;
  }
  result->points_per_scan = static_cast<std::size_t>(PerfMedian(points));
  result->cpu_s = PerfMedian(cpu), result->wall_s = PerfMedian(wall);
  result->total = Stage(total), result->deskew = Stage(desk), result->preprocess = Stage(pre);
  result->features = Stage(feat), result->registration = Stage(reg), result->fusion = Stage(fuse);
  result->map = Stage(map);
  result->deskew_error = deskew.Result();
  return Status::Ok();
}

void PrintSlamBench(const SlamBenchOptions& o, const SlamBenchResult& r, std::ostream& os) {
  char line[256];
  os << "SLAM core: scene " << o.scene << ", carrier " << o.carrier << ", " << o.duration_s << " s simulated (seed "
     << o.seed << "), " << o.repetitions << " repetition(s), " << o.threads << " thread(s)"
     << (o.camera ? ", camera fused (+2 threads: frame decoder, tracker)" : "") << "\n";
  std::snprintf(line, sizeof(line), "scans %zu, median %zu points per scan, data %.2f s\n", r.scans,
                r.points_per_scan, r.data_s);
  os << line << "stage            median [ms]   p90 [ms]\n";
  const std::pair<const char*, StageTime> rows[] = {
      {"deskew", r.deskew},   {"preprocess", r.preprocess}, {"features", r.features}, {"register", r.registration},
      {"fuse", r.fusion},     {"map", r.map},               {"total", r.total}};
  for (const auto& [name, t] : rows) {
    std::snprintf(line, sizeof(line), "%-14s %13.2f %10.2f\n", name, t.median_ms, t.p90_ms);
    os << line;
  }
  std::snprintf(line, sizeof(line), "estimator CPU %.2f s (wall %.2f s): %.1f x real time (%.1f x on wall time)\n",
                r.cpu_s, r.wall_s, r.RealTimeRatio(), r.WallRealTimeRatio());
  os << line;
  std::snprintf(line, sizeof(line), "ATE RMSE %.4f m (max %.4f m) over %zu poses, SE(3) Umeyama\n", r.ate_rmse_m,
                r.ate_max_m, r.ate_poses);
  os << line;
  const ErrorStats& d = r.deskew_error.all;
  std::snprintf(line, sizeof(line),
                "deskew error per point [mm]: median %.2f  p90 %.2f  p95 %.2f  rmse %.2f  max %.1f  (%zu points; "
                "%zu not deskewed, %zu outside truth)\n",
                1e3 * d.median_m, 1e3 * d.p90_m, 1e3 * d.p95_m, 1e3 * d.rmse_m, 1e3 * d.max_m, d.count,
                r.deskew_error.num_not_deskewed, r.deskew_error.num_outside_truth);
  os << line;
  const ErrorStats& m = r.deskew_error.scan_medians;
  std::snprintf(line, sizeof(line), "per-scan median deskew error [mm]: median %.2f  p90 %.2f  max %.2f\n",
                1e3 * m.median_m, 1e3 * m.p90_m, 1e3 * m.max_m);
  os << line;
}

Status WriteSlamBenchJson(const std::string& path, const SlamBenchOptions& o, const SlamBenchResult& r) {
  auto stats = [](const ErrorStats& s) {
    return nlohmann::json{{"count", s.count},     {"mean_m", s.mean_m}, {"median_m", s.median_m}, {"p90_m", s.p90_m},
                          {"p95_m", s.p95_m},     {"rmse_m", s.rmse_m}, {"max_m", s.max_m}};
  };
  auto stage = [](const StageTime& t) { return nlohmann::json{{"median_ms", t.median_ms}, {"p90_ms", t.p90_ms}}; };
  nlohmann::json j;
  j["options"] = {{"scene", o.scene}, {"duration_s", o.duration_s}, {"seed", o.seed}, {"carrier", o.carrier},
                  {"repetitions", o.repetitions}, {"threads", o.threads}, {"camera", o.camera},
                  {"recording", o.recording_dir}};
  j["scans"] = r.scans;
  j["points_per_scan"] = r.points_per_scan;
  j["data_s"] = r.data_s;
  j["estimator_cpu_s"] = r.cpu_s;
  j["estimator_wall_s"] = r.wall_s;
  j["real_time_ratio"] = r.RealTimeRatio();
  j["wall_real_time_ratio"] = r.WallRealTimeRatio();
  j["scan_ms"] = {{"deskew", stage(r.deskew)},     {"preprocess", stage(r.preprocess)},
                  {"features", stage(r.features)}, {"register", stage(r.registration)},
                  {"fuse", stage(r.fusion)},       {"map", stage(r.map)},
                  {"total", stage(r.total)}};
  j["ate"] = {{"rmse_m", r.ate_rmse_m}, {"max_m", r.ate_max_m}, {"poses", r.ate_poses}};
  nlohmann::json per_scan = nlohmann::json::array();
  for (std::size_t i = 0; i < r.deskew_error.per_scan.size(); ++i) {
    nlohmann::json s = stats(r.deskew_error.per_scan[i]);
    s["t_start_s"] = r.deskew_error.scan_t_start_s[i];
    per_scan.push_back(s);
  }
  j["deskew_error"] = {{"all", stats(r.deskew_error.all)},
                       {"scan_medians", stats(r.deskew_error.scan_medians)},
                       {"not_deskewed", r.deskew_error.num_not_deskewed},
                       {"outside_truth", r.deskew_error.num_outside_truth},
                       {"per_scan", per_scan}};
  std::ofstream file(path);
  file << j.dump(2) << "\n";
  return file ? Status::Ok() : Status::Error(path + ": write failed");
}

}  // namespace rotolidar::bench
