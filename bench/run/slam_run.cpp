#include "bench/run/slam_run.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <yaml-cpp/yaml.h>

#include "bench/run/atomic_write.hpp"
#include "bench/run/keyframe_db.hpp"
#include "bench/run/loop_outputs.hpp"
#include "core/pipeline/estimator_config_yaml.hpp"
#include "core/io/csv.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/io/recording.hpp"
#include "core/io/trajectory_io.hpp"
#include "core/util/log.hpp"

namespace rotolidar::bench {
namespace {

/// Appends a report; with deskew data kept (result->deskew_scan_stride > 0) drops it from the scans between
/// every k-th one, so memory follows DeskewScanStride's bound.
void Keep(ScanReport report, SlamRunResult* result) {
  const size_t k = result->deskew_scan_stride;
  if (k > 0 && result->scans.size() % k != 0) {
    report.deskew_source = {};
    report.deskewed_base = {};
  }
  result->scans.push_back(std::move(report));
}

/// The recording's time span [s], from its encoder (LoadRecording guarantees 2 samples or more): known before the
/// streamed LiDAR packets are read.
double DataSpanS(const Recording& rec) { return rec.encoder.back().t_s - rec.encoder.front().t_s; }

/// Feeds every message to the estimator in time order (packets by capture time, camera frames kCameraFrameLeadS
/// early), as a live rig would; the packets come one at a time (LidarPacketSource), so a streamed recording of any
/// length costs the memory of one packet.
/// With `snapshots`, polled after each scan (a failed write stops the snapshots and is returned at the end).
Status Playback(const Recording& rec, Estimator* estimator, SlamRunResult* result,
                const std::function<void(double)>& progress, LoopSnapshotWriter* snapshots,
                const std::atomic<bool>* stop) {
  Status snapshot_status = Status::Ok();
  size_t i_imu = 0, i_enc = 0, i_cam = 0;
  LidarPacketSource source;
  if (Status s = source.Open(rec); !s) return s;
  const double t_begin = rec.encoder.front().t_s, span_s = std::max(DataSpanS(rec), 1e-9);
  double next_report = 0.1, t_first = 0.0;
  while (const LidarPacket* next = source.Next()) {
    const LidarPacket& packet = *next;
    if (source.count() == 1) t_first = packet.t_capture_s;
    if (stop && *stop) {  // asked to stop: finish what was fed, mark the outputs partial
      result->stopped = true;
      result->data_fed_s = packet.t_capture_s - t_first;
      break;
    }
    while (i_enc < rec.encoder.size() && rec.encoder[i_enc].t_s <= packet.t_capture_s)
      estimator->Feed(rec.encoder[i_enc++]);
    while (i_imu < rec.imu.size() && rec.imu[i_imu].t_s <= packet.t_capture_s) estimator->Feed(rec.imu[i_imu++]);
    // Camera frames go kCameraFrameLeadS ahead of the packets (as a live camera's frames arrive between the LiDAR's
    // packets, not after a scan), so that the tracker's thread works while the estimator handles the scan.
    while (i_cam < rec.camera.size() && rec.camera[i_cam].t_s <= packet.t_capture_s + kCameraFrameLeadS)
      estimator->Feed(rec.camera[i_cam++]);  // decoded only when kept (in the tracker's thread)
    if (Status s = estimator->Feed(packet); !s) LOG_WARN("packet " << source.count() - 1 << ": " << s.message);
    for (ScanReport& r : estimator->Process()) Keep(std::move(r), result);
    if (snapshots && snapshot_status) snapshot_status = snapshots->Poll(*estimator);
    if (progress && (packet.t_capture_s - t_begin) / span_s >= next_report) {
      progress(std::min(1.0, (packet.t_capture_s - t_begin) / span_s));
      next_report += 0.1;
    }
  }
  if (!source.status()) return source.status();  // a streamed lidar.pcap that went bad after the input check
  while (!result->stopped && i_enc < rec.encoder.size()) estimator->Feed(rec.encoder[i_enc++]);
  while (!result->stopped && i_imu < rec.imu.size()) estimator->Feed(rec.imu[i_imu++]);
  for (ScanReport& r : estimator->Finish()) Keep(std::move(r), result);
  if (snapshots && snapshot_status) snapshot_status = snapshots->Poll(*estimator);  // Finish waited for the closer
  return snapshot_status;
}

Status WriteScanTable(const std::string& path, const std::vector<ScanReport>& scans) {
  CsvWriter csv;
  if (Status s = csv.Open(path, {"t_start_s", "t_end_s", "num_points", "num_registered", "num_rotor_fallback",
                                 "num_edge", "num_planar", "num_less_sharp", "num_less_flat", "imu_initialized",
                                 "imu_deskew", "reg_attempted", "converged", "remapped", "iterations",
                                 "edge_inliers", "planar_inliers", "initial_cost", "final_cost", "rmse_m", "degenerate",
                                 "num_degenerate", "lambda0", "lambda1", "lambda2", "lambda3", "lambda4", "lambda5",
                                 "degen_tx", "degen_ty", "degen_tz", "degen_rx", "degen_ry", "degen_rz",
                                 "deskew_ms", "preprocess_ms", "features_ms", "register_ms", "fuse_ms", "map_ms",
                                 "total_ms", "held_static", "vx_mps", "vy_mps", "vz_mps", "bgx_radps", "bgy_radps",
                                 "bgz_radps", "bax_mps2", "bay_mps2", "baz_mps2", "keyframe", "neighbour_searches",
                                 "dynamic_features", "moving_scan_features", "vacated_features", "vacated_valve",
                                 "map_judged", "map_dynamic", "vis_image",
                                 "vis_image_offset_s", "vis_frames", "vis_tracked", "vis_inliers", "vis_new",
                                 "vis_observations", "vis_lidar_depths", "vis_landmarks", "vis_factors",
                                 "vis_rejected_total", "vis_track_ms", "vis_depth_ms", "vis_sigma_px", "vis_residual_px",
                                 "vis_time_offset_s", "rotor_offset_rad", "imu_time_offset_s", "map_points",
                                 "map_removed"});
      !s)
    return s;
  for (const ScanReport& r : scans) {
    const RegistrationSummary& g = r.registration;
    const DegeneracyRecord& d = r.degeneracy;
    const ScanTimings& t = r.timings;
    std::vector<double> row = {r.t_start_s, r.t_end_s, double(r.num_points), double(r.num_registered),
                               double(r.num_rotor_fallback), double(r.features.edge), double(r.features.planar),
                               double(r.features.less_sharp), double(r.features.less_flat),
                               double(r.imu_initialized), double(r.imu_deskew), double(g.attempted),
                               double(g.converged), double(g.remapped), double(g.iterations),
                               double(g.edge_inliers), double(g.planar_inliers), g.initial_cost, g.final_cost, g.rmse_m,
                               double(d.degenerate), double(d.num_degenerate)};
    for (int i = 0; i < 6; ++i) row.push_back(d.eigenvalues[i]);
    for (int i = 0; i < 6; ++i) row.push_back(d.axis_weight[i]);
    for (double ms : {t.deskew_ms, t.preprocess_ms, t.features_ms, t.register_ms, t.fuse_ms, t.map_ms, t.total_ms})
      row.push_back(ms);
    row.push_back(double(r.held_static));
    for (const Eigen::Vector3d* v : {&r.v_world_mps, &r.bias_gyro_radps, &r.bias_accel_mps2})
      for (int i = 0; i < 3; ++i) row.push_back((*v)[i]);
    row.push_back(double(r.keyframe));
    row.push_back(double(g.neighbour_searches));
    row.push_back(double(r.num_dynamic_features));
    row.push_back(double(r.num_moving_scan_features));
    row.push_back(double(r.num_vacated_features));
    row.push_back(r.vacated_valve ? 1.0 : 0.0);
    row.push_back(double(r.map_free_space.judged));
    row.push_back(double(r.map_free_space.dynamic));
    const VisualScanReport& v = r.visual;
    for (double x : {double(v.image), v.image_offset_s, double(v.frames_tracked), double(v.tracked),
                     double(v.inliers), double(v.new_features), double(v.observations), double(v.lidar_depths),
                     double(v.landmarks), double(v.factors), double(v.rejected_total), v.track_ms, v.depth_ms,
                     v.sigma_px, v.residual_median_px, v.time_offset_s, r.rotor_offset_rad, r.imu_time_offset_s,
                     double(r.map_points), double(r.map_free_space.removed)})
      row.push_back(x);
    csv.Row(row);
  }
  return csv.Close();
}

}  // namespace

Status WriteSlamOutputs(const std::string& out_dir, const Estimator& estimator, const SlamRunResult& result) {
  const Trajectory& traj = result.trajectory;
  auto atomically = [](const std::string& path, auto write) { return WriteAtomically(path, write); };
  for (const auto& [name, format_] : {std::pair{"trajectory.tum", TrajectoryFormat::kTum},
                                      std::pair{"trajectory.kitti", TrajectoryFormat::kKitti}}) {
    const TrajectoryFormat format = format_;  // (C++17 lambdas cannot capture a structured binding)
    if (Status s = atomically(out_dir + "/" + name,
                              [&](const std::string& part) { return WriteTrajectory(part, format, traj); });
        !s)
      return s;
  }
  if (Status s = atomically(out_dir + "/trajectory_times.txt",
                            [&](const std::string& part) { return WriteKittiTimes(part, traj); });
      !s)
    return s;
  const std::vector<Eigen::Vector3d> map = estimator.map().Points();
  for (const char* name : {"map.ply", "map.pcd"})
    if (Status s = atomically(out_dir + "/" + name, [&](const std::string& part) { return SavePointCloud(part, map); });
        !s)
      return s;
  if (Status s = atomically(out_dir + "/scans.csv",
                            [&](const std::string& part) { return WriteScanTable(part, result.scans); });
      !s)
    return s;
  if (const graph::LoopCloser* loops = estimator.loop_closer()) {
    if (Status s = WriteLoopOutputs(out_dir, *loops, result.loops, result.odometry_trajectory, estimator.config());
        !s)
      return s;
  }
  YAML::Emitter out;
  EmitEstimatorConfig(out, estimator.config());  // resolved against calib.yaml
  return atomically(out_dir + "/slam_config.yaml", [&](const std::string& part) {
    std::ofstream file(part);
    file << "# Resolved estimator configuration of this run (rotolidar slam).\n" << out.c_str() << "\n";
    file.close();
    return file ? Status::Ok() : Status::Error(part + ": write failed");
  });
}

Status ClearSlamOutputs(const std::string& out_dir) {
  static const char* kFiles[] = {"trajectory.tum", "trajectory.kitti", "trajectory_times.txt", "map.ply", "map.pcd",
                                 "scans.csv", "slam_config.yaml", "metrics.json", "report.html",
                                 "trajectory_odometry.tum", "loops.csv", "loop_candidates.csv", "map_corrected.ply"};
  static const char* kFolders[] = {"keyframes", "loop_snapshots"};
  std::error_code ec;
  for (const char* f : kFiles)
    if (std::filesystem::remove(out_dir + "/" + f, ec); ec) return Status::Error(out_dir + "/" + f + ": " + ec.message());
  for (const char* d : kFolders)
    if (std::filesystem::remove_all(out_dir + "/" + d, ec); ec)
      return Status::Error(out_dir + "/" + d + ": " + ec.message());
  return Status::Ok();
}

namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

size_t DeskewScanStride(double data_span_s) {
  if (!(data_span_s > kDeskewKeepAllSpanS)) return 1;  // also NaN / negative spans: keep everything
  return static_cast<size_t>(std::ceil(data_span_s / kDeskewKeepAllSpanS));
}

void ReleaseDeskewData(SlamRunResult* result) {
  for (ScanReport& r : result->scans) {
    r.deskew_source = {};
    r.deskewed_base = {};
  }
  result->deskew_scan_stride = 0;
}

Status RunSlam(const std::string& recording_dir, const EstimatorConfig& config, const std::string& out_dir,
               SlamRunResult* result, const std::function<void(double)>& progress) {
  SlamRunOptions options;
  options.progress = progress;
  return RunSlam(recording_dir, config, out_dir, result, options);
}

Status RunSlam(const std::string& recording_dir, const EstimatorConfig& config, const std::string& out_dir,
               SlamRunResult* result, const SlamRunOptions& options) {
  std::string why;
  if (!config.Validate(&why)) return Status::Error("slam config: " + why);
  Recording rec;  // the LiDAR packets stay on disk: memory does not grow with the recording's length
  if (Status s = LoadRecording(recording_dir, PacketLoading::kStreamed, &rec); !s) return s;
  if (options.calib) rec.calib = *options.calib;
  std::vector<InputWarning> warnings;
  if (Status s = CheckRecording(rec, InputCheckConfig{}, &warnings); !s) return s;
  for (const InputWarning& w : warnings) LOG_WARN("[" << w.code << "] " << w.message);
  if (options.strict && !warnings.empty())
    return Status::Error("--strict: the recording has " + std::to_string(warnings.size()) + " problem(s):\n" +
                         InputWarningsText(warnings));
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) return Status::Error(out_dir + ": cannot create folder: " + ec.message());
  if (Status s = ClearSlamOutputs(out_dir); !s) return s;  // a folder never mixes two runs

  *result = SlamRunResult{};
  result->input_warnings = std::move(warnings);
  if (config.keep_deskewed) result->deskew_scan_stride = DeskewScanStride(DataSpanS(rec));
  Estimator estimator(rec.calib, config);
  if (graph::LoopCloser* loops = estimator.loop_closer(); loops && !config.loop_closure.vocabulary.empty()) {
    if (Status s = loops->LoadVocabulary(config.loop_closure.vocabulary); !s)
      return Status::Error("loop_closure.vocabulary: " + s.message);
    if (rec.camera.empty()) LOG_WARN(recording_dir << ": no camera frames: loop closure's stage 1 is the LiDAR's");
  }
  const auto t0 = std::chrono::steady_clock::now();
  LoopSnapshotWriter snapshots(out_dir);
  const Status playback = Playback(rec, &estimator, result, options.progress,
                                   options.loop_snapshots ? &snapshots : nullptr, options.stop);
  if (!playback) return playback;
  result->loop_snapshots = snapshots.written();
  result->wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  result->odometry_trajectory = estimator.trajectory();
  result->trajectory = estimator.trajectory();
  if (const graph::LoopCloser* loops = estimator.loop_closer()) {  // Finish waited for it
    result->trajectory = loops->Correct(estimator.trajectory());
    result->loops = loops->State();
    if (options.keep_keyframes || options.save_keyframes) result->loop_keyframes = loops->KeyframeClouds();
    if (options.save_keyframes)
      if (Status s = WriteKeyframeDatabase(out_dir + "/keyframes", result->loop_keyframes); !s) return s;
    if (!options.keep_keyframes) result->loop_keyframes = {};
  }
  result->map_points = estimator.map().NumPoints();
  result->bad_packets = estimator.bad_packets();
  result->packet_order = estimator.packet_order_counts();
  if (const PacketOrderCounts& o = result->packet_order; o.total() > 0)
    LOG_WARN(recording_dir << "/lidar.pcap: data packets out of timestamp order: " << o.reordered
                           << " reordered; dropped " << o.duplicate << " duplicate, " << o.late << " late, " << o.wild
                           << " with a wild timestamp");
  if (!result->scans.empty()) result->data_duration_s = result->scans.back().t_end_s - result->scans.front().t_start_s;
  std::vector<double> times;
  for (const auto& r : result->scans) times.push_back(r.timings.total_ms);
  result->median_scan_ms = Median(times);
  if (result->trajectory.empty()) return Status::Error(recording_dir + ": no complete LiDAR revolution in the data");
  return WriteSlamOutputs(out_dir, estimator, *result);
}

}  // namespace rotolidar::bench
