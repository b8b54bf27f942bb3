// A recording as a KITTI odometry sequence: revolutions -> deskewed bins in the base frame at the frame time.
#include "bench/run/kitti_export.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>

#include "bench/eval/trajectory_lookup.hpp"  // PoseAt: the truth interpolation the deskew metric uses
#include "core/io/recording.hpp"
#include "core/wire/scan_splitter.hpp"
#include "core/pipeline/estimator.hpp"
#include "sim/truth/truth.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;
using ProgressFn = std::function<void(double)>;

/// Return mode of the first parsable data packet (kStrongest when there is none).
Vlp16ReturnMode RecordingReturnMode(const Recording& rec) {
  for (const LidarPacket& p : rec.lidar_packets) {
    Vlp16RawPacket raw;
    if (p.payload.size() == 1206 && ParseVlp16DataPacket(p.payload.data(), p.payload.size(), &raw))
      return Vlp16ReturnMode(raw.return_mode);
  }
  return Vlp16ReturnMode::kStrongest;
}

/// Keeps every point of a single-return recording; of a dual-return one, the chosen echo (an echo that was both
/// the strongest and the last, kReturnStrongestAndLast, is either).
bool KeepReturn(Vlp16ReturnMode mode, Vlp16ReturnFilter filter, uint8_t return_type) {
  return mode != Vlp16ReturnMode::kDual || Vlp16ReturnSelected(filter, return_type);
}

/// One exported point before the bin is put in ring order: its record, ring and firing time.
struct ExportPoint {
  KittiPoint point;
  uint8_t ring = 0;
  Seconds t_s = 0.0;
};

ExportPoint MakeExportPoint(const Eigen::Vector3f& p_base, const LidarPoint& src) {
  return {{p_base.x(), p_base.y(), p_base.z(), src.intensity / 255.f}, src.ring, src.t_s};
}

/// Writes frames as they arrive (ids 0, 1, ...): the bin in ring order, top ring first, each ring in firing order
/// (so a reader finds a ring's end where the time falls back), and its per-point times; collects frame times.
class BinSink {
 public:
  BinSink(const KittiDatasetLayout& layout, KittiExportResult* result) : layout_(layout), result_(result) {}
  Status Add(Seconds t_frame_s, std::vector<ExportPoint> points) {
    std::stable_sort(points.begin(), points.end(),
                     [](const ExportPoint& a, const ExportPoint& b) { return a.ring > b.ring; });
    std::vector<KittiPoint> bin(points.size());
    std::vector<float> times(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      bin[i] = points[i].point;
      times[i] = float(points[i].t_s - t_frame_s);
    }
    const int id = int(result_->frames);
    if (Status s = WriteKittiBin(layout_.BinPath(id), bin); !s) return s;
    if (Status s = WriteKittiPointTimes(layout_.PointTimesPath(id), times); !s) return s;
    result_->times.push_back(t_frame_s);
    result_->points += points.size();
    ++result_->frames;
    return Status::Ok();
  }

 private:
  KittiDatasetLayout layout_;
  KittiExportResult* result_;
};

/// Every point at its firing time through the true T_world_lidar, into the true base frame at the scan start.
std::vector<ExportPoint> DeskewWithTruth(const LidarScan& scan, const Trajectory& base, const Trajectory& lidar,
                                         size_t* skipped) {
  std::vector<ExportPoint> out;
  Pose3 T_world_base0;
  if (!PoseAt(base, scan.t_start_s, &T_world_base0)) {
    *skipped += scan.points.size();
    return out;
  }
  const Pose3 T_base0_world = T_world_base0.inverse();
  out.reserve(scan.points.size());
  for (const LidarPoint& p : scan.points) {
    Pose3 T_world_lidar;
    if (!PoseAt(lidar, p.t_s, &T_world_lidar)) {
      ++*skipped;
      continue;
    }
    const Eigen::Vector3d q = T_base0_world * (T_world_lidar * Eigen::Vector3d(p.x_m, p.y_m, p.z_m));
    out.push_back(MakeExportPoint(q.cast<float>(), p));
  }
  return out;
}

Status ExportWithTruth(const Recording& rec, const sim::TruthLog& truth, const KittiExportOptions& o,
                       BinSink* sink, KittiExportResult* r, const ProgressFn& progress) {
  Vlp16DecoderConfig dc;
  dc.min_range_m = rec.calib.lidar.min_range_m;
  dc.max_range_m = rec.calib.lidar.max_range_m;
  dc.lidar_clock_offset_s = rec.calib.lidar_clock_offset_s;
  Vlp16Decoder decoder(rec.calib.lidar, dc);
  RevolutionSplitter splitter(0.0);
  const Vlp16ReturnMode mode = RecordingReturnMode(rec);
  std::vector<LidarPoint> points;
  std::vector<LidarScan> done;
  size_t revolutions = 0;
  const size_t n = rec.lidar_packets.size();
  for (size_t i = 0; i < n; ++i) {
    points.clear();
    if (!decoder.Decode(rec.lidar_packets[i], &points)) {
      ++r->bad_packets;
      continue;
    }
    points.erase(std::remove_if(points.begin(), points.end(),
                                [&](const LidarPoint& p) { return !KeepReturn(mode, o.return_filter, p.return_type); }),
                 points.end());
    done.clear();
    splitter.Add(points, &done);
    for (const LidarScan& scan : done) {
      if (revolutions++ == 0) continue;  // the stream starts mid-revolution
      if (Status s = sink->Add(scan.t_start_s, DeskewWithTruth(scan, truth.base, truth.lidar, &r->points_skipped));
          !s)
        return s;
    }
    if (progress && i % 2000 == 0) progress(double(i) / double(n));
  }
  return Status::Ok();  // the revolution in progress at the end is partial: not written
}

/// The estimator's own rotary transform and deskew (keep_deskewed), revolution by revolution.
Status ExportWithEstimator(const Recording& rec, const KittiExportOptions& o, BinSink* sink, KittiExportResult* r,
                           const ProgressFn& progress) {
  EstimatorConfig config = o.estimator;
  config.keep_deskewed = true;
  Estimator estimator(rec.calib, config);
  const Vlp16ReturnMode mode = RecordingReturnMode(rec);
  // The newest report waits for the next one: report 0 (the partial first revolution) and the last (the flushed
  // partial one) are never written.
  std::optional<ScanReport> held;
  size_t held_index = 0, next_index = 0;
  auto write_held = [&]() -> Status {
    std::vector<ExportPoint> bin;
    for (size_t k = 0; k < held->deskewed_base.size(); ++k) {
      const Eigen::Vector3f& q = held->deskewed_base[k];
      const LidarPoint& src = held->deskew_source[k];
      if (!KeepReturn(mode, o.return_filter, src.return_type)) continue;
      if (!q.allFinite()) {
        ++r->points_skipped;
        continue;
      }
      bin.push_back(MakeExportPoint(q, src));
    }
    return sink->Add(held->t_start_s, std::move(bin));
  };
  auto take = [&](std::vector<ScanReport> reports) -> Status {
    for (ScanReport& report : reports) {
      if (held && held_index > 0)
        if (Status s = write_held(); !s) return s;
      held = std::move(report);
      held_index = next_index++;
    }
    return Status::Ok();
  };
  size_t i_imu = 0, i_enc = 0;
  const size_t n = rec.lidar_packets.size();
  for (size_t i = 0; i < n; ++i) {
    const LidarPacket& packet = rec.lidar_packets[i];
    while (i_enc < rec.encoder.size() && rec.encoder[i_enc].t_s <= packet.t_capture_s)
      estimator.Feed(rec.encoder[i_enc++]);
    while (i_imu < rec.imu.size() && rec.imu[i_imu].t_s <= packet.t_capture_s) estimator.Feed(rec.imu[i_imu++]);
    if (!estimator.Feed(packet)) ++r->bad_packets;
    if (Status s = take(estimator.Process()); !s) return s;
    if (progress && i % 2000 == 0) progress(double(i) / double(n));
  }
  while (i_enc < rec.encoder.size()) estimator.Feed(rec.encoder[i_enc++]);
  while (i_imu < rec.imu.size()) estimator.Feed(rec.imu[i_imu++]);
  return take(estimator.Finish());
}

KittiCalib RigAsKittiCalib(const RigCalib& calib) {
  KittiCalib k;
  Matrix34d P = Matrix34d::Zero();
  P(0, 0) = calib.camera.fx_px;
  P(1, 1) = calib.camera.fy_px;
  P(0, 2) = calib.camera.cx_px;
  P(1, 2) = calib.camera.cy_px;
  P(2, 2) = 1.0;
  k.P = {P, P, P, P};  // one camera: no stereo baseline
  k.T_cam0_velo = calib.T_base_cam.inverse();  // velodyne = base
  return k;
}

Status WritePosesFromTruth(const Trajectory& base, const KittiDatasetLayout& layout, KittiExportResult* r) {
  Pose3 T_world_base0;
  if (r->times.empty() || !PoseAt(base, r->times.front(), &T_world_base0))
    return Status::Error(layout.PosesPath() + ": the truth does not cover the first frame");
  for (Seconds t : r->times) {
    Pose3 T_world_base;
    if (!PoseAt(base, t, &T_world_base))
      return Status::Error(layout.PosesPath() + ": the truth does not cover t = " + std::to_string(t) + " s");
    r->poses.push_back(VeloToCam0Pose(r->calib.T_cam0_velo, T_world_base0.inverse() * T_world_base));
  }
  r->wrote_poses = true;
  return WriteKittiPoses(layout.PosesPath(), r->poses);
}

/// What sequence_info.txt states about the export.
KittiSequenceInfo ExportInfo(const KittiExportOptions& o, const RigCalib& calib, Vlp16ReturnMode mode) {
  KittiSequenceInfo info;
  info.sensor = "VLP-16 on a rotor (rotolidar rig)";
  info.scan_lines = 16;
  info.range_sigma_m = calib.lidar.range_sigma_m;  // calib.yaml's: the features' noise gate needs it
  info.rotor_deg_per_scan = std::abs(calib.motor_speed_radps) * 60.0 / calib.lidar.rpm * 180.0 / M_PI;
  info.point_order = "rings top first (ring 15 .. 0 by the lasers' elevation), each ring in firing order";
  info.point_times = "velodyne_times/%06d.bin: float32 [s] after the frame's times.txt entry, one per point in the "
                     "bin's order";
  info.frame = "velodyne = the rig's base frame at the frame time (the revolution's first return), not the sensor";
  info.deskew = KittiDeskewDescription(o.deskew);
  info.returns = mode != Vlp16ReturnMode::kDual ? std::string("single-return recording: every return")
                 : o.return_filter == Vlp16ReturnFilter::kLast ? std::string("dual-return recording: last")
                                                               : std::string("dual-return recording: strongest");
  info.source = "rotolidar export of recording " + o.recording_dir;
  return info;
}

}  // namespace

bool ParseKittiDeskewSource(const std::string& name, KittiDeskewSource* out) {
  if (name == "truth") *out = KittiDeskewSource::kTruth;
  else if (name == "estimator") *out = KittiDeskewSource::kEstimator;
  else return false;
  return true;
}

std::string KittiDeskewDescription(KittiDeskewSource source) {
  return source == KittiDeskewSource::kTruth
             ? "truth (the simulation's ground truth: exact rotor angle and carrier motion, which no real rig has)"
             : "estimator (the core's own rotary transform from the encoder and motion compensation: an estimate)";
}

bool KittiExportOptions::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (recording_dir.empty()) return fail("export: no recording folder");
  if (out_dir.empty()) return fail("export: no output folder (--kitti)");
  if (sequence.empty() || sequence.find('/') != std::string::npos)
    return fail("export: sequence must be a folder name (got '" + sequence + "')");
  if (return_filter == Vlp16ReturnFilter::kAll) return fail("export: return_filter must be strongest or last");
  std::string why;
  if (!estimator.Validate(&why)) return fail("slam config: " + why);
  return true;
}

Status ExportKitti(const KittiExportOptions& options, KittiExportResult* result, const ProgressFn& progress) {
  std::string why;
  if (!options.Validate(&why)) return Status::Error(why);
  Recording rec;
  if (Status s = LoadRecording(options.recording_dir, &rec); !s) return s;
  const std::string truth_dir = options.recording_dir + "/truth";
  const bool has_truth = fs::exists(truth_dir + "/base.tum") && fs::exists(truth_dir + "/lidar.tum");
  if (options.deskew == KittiDeskewSource::kTruth && !has_truth)
    return Status::Error(truth_dir + ": no base.tum / lidar.tum: truth deskew needs a simulated recording");
  sim::TruthLog truth;
  if (has_truth) {
    if (Status s = sim::ReadTum(truth_dir + "/base.tum", &truth.base); !s) return s;
    if (Status s = sim::ReadTum(truth_dir + "/lidar.tum", &truth.lidar); !s) return s;
  }
  KittiDatasetLayout layout;
  layout.root = options.out_dir;
  layout.name = options.sequence;
  if (Status s = CreateKittiDatasetFolders(layout, /*point_times=*/true); !s) return s;

  KittiExportResult r;
  r.sequence_dir = layout.SequenceDir();
  r.calib = RigAsKittiCalib(rec.calib);
  r.deskew = options.deskew;
  r.deskewed_with_truth = options.deskew == KittiDeskewSource::kTruth;
  BinSink sink(layout, &r);
  Status s = r.deskewed_with_truth ? ExportWithTruth(rec, truth, options, &sink, &r, progress)
                                   : ExportWithEstimator(rec, options, &sink, &r, progress);
  if (!s) return s;
  if (r.frames == 0) return Status::Error(options.recording_dir + ": no complete LiDAR revolution to export");
  if (Status w = WriteKittiTimeList(layout.TimesPath(), r.times); !w) return w;
  if (Status w = WriteKittiCalib(layout.CalibPath(), r.calib); !w) return w;
  r.info_path = layout.InfoPath();
  if (Status w = WriteKittiSequenceInfo(r.info_path, ExportInfo(options, rec.calib, RecordingReturnMode(rec))); !w) return w;
  if (has_truth)
    if (Status w = WritePosesFromTruth(truth.base, layout, &r); !w) return w;
  *result = std::move(r);
  return Status::Ok();
}

}  // namespace rotolidar::bench
