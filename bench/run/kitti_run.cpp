#include "bench/run/kitti_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "bench/run/loop_outputs.hpp"
#include "bench/run/scan_health.hpp"
#include "core/pipeline/estimator_config_yaml.hpp"
#include "core/io/csv.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/io/trajectory_io.hpp"

namespace rotolidar::bench {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// Indices into sequence.frame_ids of the frames to use.
std::vector<size_t> SelectFrames(const KittiSequence& seq, const KittiRunOptions& o) {
  std::vector<size_t> picked;
  for (size_t i = 0; i < seq.frame_ids.size(); ++i) {
    if (seq.frame_ids[i] < o.start_frame) continue;
    if (o.max_frames > 0 && picked.size() >= size_t(o.max_frames)) break;
    picked.push_back(i);
  }
  return picked;
}

/// "5, 7-9, 12" for ascending ids: the first `limit` runs, then "...".
std::string IdRuns(const std::vector<std::pair<int, int>>& runs, size_t limit = 10) {
  std::string text;
  for (size_t k = 0; k < runs.size() && k < limit; ++k) {
    if (k > 0) text += ", ";
    text += std::to_string(runs[k].first);
    if (runs[k].second > runs[k].first) text += "-" + std::to_string(runs[k].second);
  }
  return runs.size() > limit ? text + ", ..." : text;
}

/// Bin i of the sequence as ScanPoints: lines split by its per-point times when the sequence has them, else by
/// azimuth (KittiScanPoints). Errors name the file.
Status ScanPointsOf(const KittiSequence& seq, size_t i, Seconds t_s, const KittiScanConfig& config,
                    std::vector<ScanPoint>* points, KittiScanStats* stats) {
  std::vector<KittiPoint> bin;
  if (Status s = ReadKittiBin(seq.bin_paths[i], &bin); !s) return s;
  Status s;
  if (seq.point_time_paths.empty()) {
    s = KittiScanPoints(bin, t_s, config, points, stats);
  } else {
    std::vector<float> times;
    if (Status read = ReadKittiPointTimes(seq.point_time_paths[i], &times); !read) return read;
    if (times.size() != bin.size())
      return Status::Error(seq.point_time_paths[i] + ": " + std::to_string(times.size()) + " point times for the " +
                           std::to_string(bin.size()) + " points of " + seq.bin_paths[i]);
    s = KittiScanPoints(bin, times, t_s, config, points, stats);
  }
  return s ? s : Status::Error(seq.bin_paths[i] + ": " + s.message);
}

/// The sensor's range noise (the config's, else sequence_info.txt's, else the KITTI default) and the scan lines
/// every frame should have (the option, else sequence_info.txt's, else 0: the first frame's).
void ResolveSensor(const KittiSequence& seq, const KittiRunOptions& o, KittiRunResult* r) {
  r->rotor_deg_per_scan = seq.info.rotor_deg_per_scan;
  r->range_sigma_m = seq.info.range_sigma_m > 0.0 ? seq.info.range_sigma_m : kKittiDefaultRangeSigmaM;
  r->range_sigma_source = seq.info.range_sigma_m > 0.0 ? seq.info_path : "default";
  if (o.estimator.features.range_sigma_m != kRangeSigmaFromCalib) {
    r->range_sigma_m = o.estimator.features.range_sigma_m;
    r->range_sigma_source = "config";
  }
  if (o.scan.expected_lines > 0) {
    r->expected_lines = o.scan.expected_lines;
    r->expected_lines_source = "option";
  } else if (seq.info.scan_lines > 0) {
    r->expected_lines = seq.info.scan_lines;
    r->expected_lines_source = seq.info_path;
  }
}

/// The run's calibration: base = velodyne (no IMU, identity extrinsics), the sensor's range noise, and a rotary
/// rig's rotor speed at the nominal 600 rpm head (from its angle per frame: it sets the keyframe policy).
RigCalib KittiRunCalib(const KittiSequence& seq, const KittiRunResult& r) {
  RigCalib calib;
  if (r.imu_used) calib.T_base_imu = seq.imu_calib.T_velo_imu;
  calib.lidar.range_sigma_m = r.range_sigma_m;
  calib.motor_speed_radps = r.rotor_deg_per_scan * M_PI / 180.0 * calib.lidar.rpm / 60.0;
  return calib;
}

/// The estimator config as the run uses it: the options' with use_imu as resolved (the sequence's IMU, --imu).
EstimatorConfig RunEstimatorConfig(const KittiRunOptions& o, const KittiRunResult& r) {
  EstimatorConfig config = o.estimator;
  config.use_imu = r.imu_used;
  return config;
}

/// Feeds the picked frames to a fresh estimator; fills the per-frame parts of *r and the dense map [velo(first)].
Status RunFrames(const KittiSequence& seq, const std::vector<size_t>& picked, const KittiRunOptions& o,
                 KittiRunResult* r, std::vector<Eigen::Vector3d>* map,
                 const std::function<void(double)>& progress) {
  Estimator estimator(KittiRunCalib(seq, *r), RunEstimatorConfig(o, *r));
  double estimator_s = 0.0;
  size_t next_imu = 0;
  size_t next_report = picked.size() / 10;
  for (size_t n = 0; n < picked.size(); ++n) {
    const size_t i = picked[n];
    const int id = seq.frame_ids[i];
    const Seconds t_s = seq.times[size_t(id)];
    std::vector<ScanPoint> points;
    KittiScanStats stats;
    if (Status s = ScanPointsOf(seq, i, t_s, o.scan, &points, &stats); !s) return s;
    if (r->expected_lines == 0) {
      r->expected_lines = int(stats.num_lines);
      r->expected_lines_source = "first frame";
    }
    r->scan_lines.push_back(stats.num_lines);
    r->frames_other_line_count += stats.num_lines != size_t(r->expected_lines) ? 1 : 0;
    r->elevation_inversions += stats.elevation_inversions;
    const auto t0 = std::chrono::steady_clock::now();
    Seconds t_last_s = t_s;  // the IMU must reach the last point for a deskew
    if (r->deskewed)
      for (const ScanPoint& q : points) t_last_s = std::max(t_last_s, q.t_s);
    // Up to and including the first sample after t_last_s (it brackets the frame's end).
    for (; r->imu_used && next_imu < seq.imu.size() && (next_imu == 0 || seq.imu[next_imu - 1].t_s <= t_last_s);
         ++next_imu) {
      estimator.Feed(seq.imu[next_imu]);
      ++r->imu_samples_fed;
    }
    r->scans.push_back(r->deskewed ? estimator.ProcessTimedScan(t_s, std::move(points))
                                   : estimator.ProcessDeskewedScan(t_s, std::move(points)));
    r->frames_imu_initialized += r->scans.back().imu_initialized ? 1 : 0;
    estimator_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r->frame_ids.push_back(id);
    if (progress && n >= next_report) {
      progress(double(n) / double(picked.size()));
      next_report += std::max<size_t>(1, picked.size() / 10);
    }
  }
  r->wall_time_s = estimator_s;
  estimator.FinishLoopClosure();
  r->trajectory_velo = estimator.trajectory();
  if (const graph::LoopCloser* loops = estimator.loop_closer()) {
    r->loop_closure = true;
    r->loops = loops->State();
    for (const StampedPose& p : estimator.trajectory())
      r->odometry_cam0.push_back({p.t_s, VeloToCam0Pose(seq.calib.T_cam0_velo, p.T_ref_body)});
    r->trajectory_velo = loops->Correct(estimator.trajectory());
    // trajectory_odometry.tum in the cam0 convention of trajectory.tum; map_corrected.ply in velo(first).
    if (Status s = WriteLoopOutputs(o.out_dir, *loops, r->loops, r->odometry_cam0, estimator.config()); !s) return s;
  }
  if (r->trajectory_velo.size() != r->scans.size())
    return Status::Error("estimator returned " + std::to_string(r->trajectory_velo.size()) + " poses for " +
                         std::to_string(r->scans.size()) + " frames");
  const FreeSpaceCounts flushed = estimator.FlushMap();  // the last free_space.delay_s of points
  if (!r->scans.empty()) r->scans.back().map_free_space += flushed;
  *map = estimator.map().Points();
  r->map_points = map->size();
  std::vector<double> ms;
  for (const ScanReport& s : r->scans) ms.push_back(s.timings.total_ms);
  r->median_scan_ms = Median(ms);
  return Status::Ok();
}

/// APE (none, SE(3)) and consecutive-frame RPE (translation, angle) of trajectory_cam0 against the ground truth.
void Evaluate(const KittiSequence& seq, KittiRunResult* r) {
  const Pose3 T_first_inv = seq.poses[size_t(r->frame_ids.front())].inverse();
  for (size_t n = 0; n < r->frame_ids.size(); ++n)
    r->ground_truth_cam0.push_back({r->trajectory_cam0[n].t_s, T_first_inv * seq.poses[size_t(r->frame_ids[n])]});
  r->has_ground_truth = true;
  r->poses_path = seq.poses_path;
  EvalOptions o;
  o.align = Alignment::kNone;
  r->ape = EvaluateTrajectories(r->ground_truth_cam0, r->trajectory_cam0, o, false);
  o.align = Alignment::kSe3;
  r->ape_se3 = EvaluateTrajectories(r->ground_truth_cam0, r->trajectory_cam0, o, false);
  if (r->loop_closure) {
    r->ape_se3_odometry = EvaluateTrajectories(r->ground_truth_cam0, r->odometry_cam0, o, false);
    o.align = Alignment::kNone;
    r->ape_odometry = EvaluateTrajectories(r->ground_truth_cam0, r->odometry_cam0, o, false);
  }
  o.align = Alignment::kNone;
  o.metric = EvalMetric::kRpe;
  o.delta = 1.0;
  r->rpe_translation = EvaluateTrajectories(r->ground_truth_cam0, r->trajectory_cam0, o, false);
  o.pose_relation = PoseRelation::kRotationAngleDeg;
  r->rpe_rotation = EvaluateTrajectories(r->ground_truth_cam0, r->trajectory_cam0, o, false);
}

Status WriteScanTable(const std::string& path, const KittiRunResult& r) {
  CsvWriter csv;
  if (Status s = csv.Open(path, {"t_s", "frame", "num_points", "num_registered", "scan_lines", "edge", "planar",
                                 "converged", "iterations", "edge_inliers", "planar_inliers", "rmse_m",
                                 "degenerate", "total_ms"});
      !s)
    return s;
  for (size_t n = 0; n < r.scans.size(); ++n) {
    const ScanReport& s = r.scans[n];
    csv.Row({s.t_start_s, double(r.frame_ids[n]), double(s.num_points), double(s.num_registered),
             double(r.scan_lines[n]), double(s.features.edge), double(s.features.planar),
             double(s.registration.converged), double(s.registration.iterations),
             double(s.registration.edge_inliers), double(s.registration.planar_inliers), s.registration.rmse_m,
             double(s.degeneracy.degenerate), s.timings.total_ms});
  }
  return csv.Close();
}

nlohmann::json StatsJson(const EvalResult& e, const char* alignment) {
  if (!e.status) return {{"error", e.status.message}};
  const ErrorStatistics& s = e.stats;
  return {{"alignment", alignment}, {"count", s.count}, {"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median},
          {"std", s.std}, {"min", s.min}, {"max", s.max}};
}

Status WriteMetrics(const std::string& path, const KittiSequence& seq, const KittiRunOptions& o,
                    const KittiRunResult& r) {
  nlohmann::json j;
  j["sequence"] = o.paths.dir;
  j["calib"] = seq.calib_path;
  j["times"] = seq.nominal_times ? "nominal 10 Hz" : seq.times_path;
  j["frames"] = r.frame_ids.size();
  j["first_frame"] = r.frame_ids.front();
  j["scan_lines"] = {{"expected", r.expected_lines},
                     {"expected_from", r.expected_lines_source},
                     {"split_by", seq.point_time_paths.empty() ? "azimuth" : "point times"},
                     {"frames_other_count", r.frames_other_line_count},
                     {"elevation_inversions", r.elevation_inversions}};
  j["range_sigma_m"] = {{"value", r.range_sigma_m}, {"from", r.range_sigma_source}};
  j["deskew"] = r.deskewed ? "estimator (per-point times)" : "none (bins taken as compensated)";
  j["imu"] = {{"used", r.imu_used}, {"file", seq.imu_path}, {"calib", seq.imu_calib_path},
              {"samples_fed", r.imu_samples_fed}, {"frames_from_window", r.frames_imu_initialized}};
  j["slam"] = {{"wall_time_s", r.wall_time_s}, {"median_scan_ms", r.median_scan_ms}, {"map_points", r.map_points}};
  j["health"] = ScanHealthJson(AssessScanHealth(r.scans));
  j["input_warnings"] = nlohmann::json::array();
  for (const InputWarning& w : r.input_warnings)
    j["input_warnings"].push_back({{"code", w.code}, {"count", w.count}, {"message", w.message}});
  if (r.has_ground_truth) {
    j["ground_truth"] = seq.poses_path;
    j["ape_translation_m"] = StatsJson(r.ape, "none");
    j["ape_translation_m_se3"] = StatsJson(r.ape_se3, "se3");
    j["rpe_translation_m"] = StatsJson(r.rpe_translation, "none");
    j["rpe_rotation_deg"] = StatsJson(r.rpe_rotation, "none");
    j["rpe_delta"] = "1 frame";
  }
  if (r.loop_closure) {
    size_t rejected = 0;
    for (const graph::LoopRecord& l : r.loops.loops) rejected += l.rejected ? 1 : 0;
    j["loop_closure"] = {{"keyframes", r.loops.keyframes.size()}, {"loops", r.loops.loops.size()},
                         {"rejected_by_graph", rejected}, {"graph_solves", r.loops.graph_solves},
                         {"max_solve_time_s", r.loops.max_solve_time_s}, {"verify_time_s", r.loops.verify_time_s}};
    if (r.has_ground_truth) {
      j["loop_closure"]["ape_translation_m_odometry"] = StatsJson(r.ape_odometry, "none");
      j["loop_closure"]["ape_translation_m_se3_odometry"] = StatsJson(r.ape_se3_odometry, "se3");
    }
  }
  std::ofstream file(path);
  file << j.dump(2) << "\n";
  return file ? Status::Ok() : Status::Error(path + ": write failed");
}

Status WriteOutputs(const KittiSequence& seq, const KittiRunOptions& o, const std::vector<Eigen::Vector3d>& map,
                    const KittiRunResult& r) {
  const std::string& d = o.out_dir;
  std::vector<Pose3> cam0;
  std::vector<Seconds> times;
  for (const StampedPose& p : r.trajectory_cam0) {
    cam0.push_back(p.T_ref_body);
    times.push_back(p.t_s);
  }
  if (Status s = WriteKittiPoses(d + "/trajectory.kitti", cam0); !s) return s;
  if (Status s = WriteTrajectory(d + "/trajectory.tum", TrajectoryFormat::kTum, r.trajectory_cam0); !s) return s;
  if (Status s = WriteTrajectory(d + "/trajectory_velo.tum", TrajectoryFormat::kTum, r.trajectory_velo); !s) return s;
  if (Status s = WriteKittiTimeList(d + "/times.txt", times); !s) return s;
  if (Status s = SavePointCloud(d + "/map.ply", map); !s) return s;
  if (Status s = WriteScanTable(d + "/scans.csv", r); !s) return s;
  YAML::Emitter out;
  EmitEstimatorConfig(out, ResolveFromCalib(RunEstimatorConfig(o, r), KittiRunCalib(seq, r)));  // as the estimator ran
  std::ofstream file(d + "/slam_config.yaml");
  file << "# Resolved estimator configuration of this run (rotolidar slam --kitti).\n" << out.c_str() << "\n";
  if (!file) return Status::Error(d + "/slam_config.yaml: write failed");
  return WriteMetrics(d + "/metrics.json", seq, o, r);
}

}  // namespace

std::vector<InputWarning> CheckKittiFrames(const KittiSequence& seq, const std::vector<size_t>& picked) {
  std::vector<std::pair<int, int>> missing, empty;
  size_t missing_count = 0;
  for (size_t n = 0; n < picked.size(); ++n) {
    const int id = seq.frame_ids[picked[n]];
    if (n > 0 && id > seq.frame_ids[picked[n - 1]] + 1) {
      missing.emplace_back(seq.frame_ids[picked[n - 1]] + 1, id - 1);
      missing_count += size_t(id - 1 - seq.frame_ids[picked[n - 1]]);
    }
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(seq.bin_paths[picked[n]], ec);
    if (!ec && bytes < sizeof(float) * 4) empty.emplace_back(id, id);
  }
  std::vector<InputWarning> warnings;
  const std::string dir = std::filesystem::path(seq.bin_paths.front()).parent_path().string();
  if (missing_count > 0)
    warnings.push_back({"kitti.missing_frames",
                        dir + ": " + std::to_string(missing_count) + (missing_count == 1 ? " frame" : " frames") +
                            " missing between frames " +
                            std::to_string(seq.frame_ids[picked.front()]) + " and " +
                            std::to_string(seq.frame_ids[picked.back()]) + " (ids " + IdRuns(missing) +
                            "): the estimator bridges each gap as one longer step",
                        missing_count});
  if (!empty.empty())
    warnings.push_back({"kitti.empty_frames",
                        dir + ": " + std::to_string(empty.size()) + (empty.size() == 1 ? " bin" : " bins") +
                            " without a point (ids " + IdRuns(empty) +
                            "): those frames are predicted, not registered",
                        empty.size()});
  return warnings;
}

bool ParseKittiSwitch(const std::string& word, KittiSwitch* value) {
  if (word == "auto") *value = KittiSwitch::kAuto;
  else if (word == "on") *value = KittiSwitch::kOn;
  else if (word == "off") *value = KittiSwitch::kOff;
  else return false;
  return true;
}

EstimatorConfig KittiEstimatorConfig() {
  EstimatorConfig c;
  c.preprocess.min_range_m = 2.0;
  c.preprocess.max_range_m = 80.0;
  // A KITTI frame is a whole revolution, with none of the rotary fan's sky-and-ground phases that the LiDAR-only
  // velocity window and rebuild cap are for: the last two frames' twist and the registration's own cap, as
  // docs/kitti.md measured them.
  c.lidar_only_velocity_window_s = 0.0;
  c.lidar_only_max_correspondence_rebuilds = c.registration.max_correspondence_rebuilds;
  // features.range_sigma_m stays kRangeSigmaFromCalib: the run's calibration holds sequence_info.txt's
  // range_sigma_m, else kKittiDefaultRangeSigmaM.
  return c;
}

bool KittiRunOptions::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (paths.dir.empty()) return fail("kitti: no sequence folder");
  if (start_frame < 0) return fail("kitti: start_frame must be >= 0 (got " + std::to_string(start_frame) + ")");
  if (max_frames < 0) return fail("kitti: max_frames must be >= 0 (got " + std::to_string(max_frames) + ")");
  if (out_dir.empty()) return fail("kitti: no output folder");
  std::string why;
  if (!estimator.Validate(&why)) return fail("slam config: " + why);
  if (!scan.Validate(&why)) return fail(why);
  return true;
}

Status RunKitti(const KittiRunOptions& options, KittiRunResult* result,
                const std::function<void(double)>& progress) {
  std::string why;
  if (!options.Validate(&why)) return Status::Error(why);
  KittiSequence seq;
  if (Status s = OpenKittiSequence(options.paths, &seq); !s) return s;
  const std::vector<size_t> picked = SelectFrames(seq, options);
  if (picked.empty())
    return Status::Error(options.paths.dir + ": no frame with id >= " + std::to_string(options.start_frame));
  std::error_code ec;
  std::filesystem::create_directories(options.out_dir, ec);
  if (ec) return Status::Error(options.out_dir + ": cannot create folder: " + ec.message());

  KittiRunResult r;
  r.input_warnings = CheckKittiFrames(seq, picked);
  if (options.strict && !r.input_warnings.empty())
    return Status::Error("--strict: " + r.input_warnings.front().message);
  r.nominal_times = seq.nominal_times;
  r.point_times = !seq.point_time_paths.empty();
  if (options.imu == KittiSwitch::kOn && seq.imu.empty())
    return Status::Error(options.paths.dir + ": --imu on, but the sequence has no imu.csv");
  r.imu_used = options.imu != KittiSwitch::kOff && options.estimator.use_imu && !seq.imu.empty();
  r.deskewed = options.deskew == KittiSwitch::kOn ||
               (options.deskew == KittiSwitch::kAuto && seq.info.deskew.rfind("none", 0) == 0);
  ResolveSensor(seq, options, &r);
  std::vector<Eigen::Vector3d> map;
  if (Status s = RunFrames(seq, picked, options, &r, &map, progress); !s) return s;
  for (const StampedPose& p : r.trajectory_velo)
    r.trajectory_cam0.push_back({p.t_s, VeloToCam0Pose(seq.calib.T_cam0_velo, p.T_ref_body)});
  if (!seq.poses.empty()) Evaluate(seq, &r);
  *result = std::move(r);
  return WriteOutputs(seq, options, map, *result);
}

}  // namespace rotolidar::bench
