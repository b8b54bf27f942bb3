// The estimator's data flow: message buffering, the per-scan pipeline (ProcessScan reads like the seed's Sec. 3)
// and the deskew / preprocess / feature stages. Registration, fusion and mapping: estimator_fuse.cpp.
#include "core/pipeline/estimator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "core/pipeline/estimator_internal.hpp"
#include "core/util/log.hpp"

namespace rotolidar {
namespace {

Vlp16DecoderConfig DecoderConfigFor(const RigCalib& calib) {
  Vlp16DecoderConfig c;
  c.min_range_m = calib.lidar.min_range_m;
  c.max_range_m = calib.lidar.max_range_m;
  c.lidar_clock_offset_s = calib.lidar_clock_offset_s;
  return c;
}

/// The sensor origin in the base frame for the free-space images: the lidar origin averaged over a rotor turn
/// (on the motor axis it does not move; off the axis this is its circle's centre).
Eigen::Vector3d SensorOrigin(const RigCalib& calib) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k) sum += calib.T_base_lidar(0.5 * M_PI * k).translation();
  return 0.25 * sum;
}

}  // namespace

Estimator::Estimator(const RigCalib& calib, const EstimatorConfig& config)
    : calib_(calib),
      config_(ResolveFromCalib(config, calib)),
      orderer_(config.packet_order),
      decoder_(calib_.lidar, DecoderConfigFor(calib_)),
      splitter_(config.cut_azimuth_deg),
      rotor_(calib_),
      local_map_(config.local_map),
      dense_map_(config.output_map_voxel_m, config.output_map_points_per_voxel) {
  std::string why;
  ROTOLIDAR_CHECK(calib_.Validate(&why), why);
  ROTOLIDAR_CHECK(config_.Validate(&why), why);
  if (config_.free_space.enabled)
    free_space_ = std::make_unique<FreeSpaceFilter>(config_.free_space, SensorOrigin(calib_));
  if (config_.free_space.enabled && config_.free_space.recheck_s > 0)
    map_recheck_ = std::make_unique<MapRecheck>(config_.free_space);
  const FreeSpaceConfig& fs = config_.free_space;
  if (fs.enabled && fs.screen_scan_features && fs.vacated_radius_m > 0 && config_.use_imu)  // IMU prediction only
    vacated_ = std::make_unique<VacatedScreen>(config_.free_space, SensorOrigin(calib_));
  if (config_.loop_closure.enabled) loop_closer_ = std::make_unique<graph::LoopCloser>(config_.loop_closure);
  if (config_.visual.enabled) visual_ = std::make_unique<VisualFrontEnd>(config_.visual, calib_);
}

void Estimator::FinishLoopClosure() {
  if (loop_closer_) loop_closer_->Finish();
}

Estimator::~Estimator() = default;

bool Estimator::imu_initialized() const { return window_ && window_->initialized(); }

void Estimator::Feed(const EncoderSample& sample) { rotor_.Add(sample); }

// IMU stamps move to rig time by calib.yaml's imu_time_offset_s and the window's correction of it
// (window.estimate_time_offset; else 0). The correction moves by at most half a millisecond per scan (Fuse), less
// than the samples' spacing, so the order holds.
void Estimator::Feed(const ImuSample& sample) {
  if (!config_.use_imu) return;
  const Seconds t_s = sample.t_s - calib_.imu_time_offset_s - imu_time_offset_s_;
  if (!imu_.empty() && !(t_s > imu_.back().t_s)) return;
  imu_.push_back(sample);
  imu_.back().t_s = t_s;
}

Status Estimator::Feed(const LidarPacket& packet) {
  ordered_.clear();
  orderer_.Push(packet, &ordered_);
  return DecodeOrdered();
}

// Decodes the packets the orderer released and cuts revolutions; returns the first decode error.
Status Estimator::DecodeOrdered() {
  Status first = Status::Ok();
  for (const LidarPacket& p : ordered_) {
    packet_points_.clear();
    if (Status s = decoder_.Decode(p, &packet_points_); !s) {
      ++bad_packets_;
      if (first) first = s;
      continue;
    }
    std::vector<LidarScan> completed;
    splitter_.Add(packet_points_, &completed);
    for (auto& scan : completed) pending_scans_.push_back(std::move(scan));
  }
  ordered_.clear();
  return first;
}

std::vector<ScanReport> Estimator::Process() {
  std::vector<ScanReport> reports;
  while (!pending_scans_.empty() && !rotor_.empty()) {
    // Wait until the encoder (and the IMU, once it streams) has covered the scan, or data ends (Finish).
    const Seconds t_end = pending_scans_.front().t_end_s;
    if (rotor_.last_time_s() < t_end) break;
    if (!imu_.empty() && imu_.back().t_s < t_end) break;
    reports.push_back(ProcessScan(pending_scans_.front()));
    pending_scans_.pop_front();
  }
  return reports;
}

size_t Estimator::DropPendingScans(size_t keep) {
  size_t dropped = 0;
  while (pending_scans_.size() > keep) {
    pending_scans_.pop_front();
    ++dropped;
  }
  return dropped;
}

std::vector<ScanReport> Estimator::Finish() {
  orderer_.Flush(&ordered_);
  if (Status s = DecodeOrdered(); !s) LOG_WARN("last packets: " << s.message);
  if (auto last = splitter_.Flush()) pending_scans_.push_back(std::move(*last));
  std::vector<ScanReport> reports;
  while (!pending_scans_.empty()) {
    reports.push_back(ProcessScan(pending_scans_.front()));
    pending_scans_.pop_front();
  }
  const FreeSpaceCounts flushed = FlushMap();  // the last delay_s of points, in the last scan's report
  if (!reports.empty()) reports.back().map_free_space += flushed;
  FinishLoopClosure();
  return reports;
}

// The seed's pipeline for one revolution: Deskew -> ExtractFeatures -> Register -> Fuse -> UpdateMap.
ScanReport Estimator::ProcessScan(const LidarScan& scan) {
  const Stopwatch total;
  ScanReport report;
  report.t_start_s = scan.t_start_s;
  report.t_end_s = scan.t_end_s;
  report.num_points = scan.points.size();
  const Prediction prediction = Predict(scan.t_start_s, scan.t_end_s);
  std::vector<ScanPoint> points = Deskew(scan, prediction, &report);
  ProcessCloud(scan.t_start_s, std::move(points), prediction, &report);
  RecordMeasuredPose(scan.t_start_s, scan.t_end_s, &prediction.motion);
  rotor_.DropBefore(scan.t_end_s - 1.0);
  report.timings.total_ms = total.ms();
  return report;
}

ScanReport Estimator::ProcessDeskewedScan(Seconds t_s, std::vector<ScanPoint> points) {
  return ProcessBaseFrameScan(t_s, std::move(points), false);
}

ScanReport Estimator::ProcessTimedScan(Seconds t_s, std::vector<ScanPoint> points) {
  return ProcessBaseFrameScan(t_s, std::move(points), true);
}

// A cloud already in the base frame; with `deskew`, the carrier's motion over the revolution first moves each
// point from its own time to t_s. Then the shared back half.
ScanReport Estimator::ProcessBaseFrameScan(Seconds t_s, std::vector<ScanPoint> points, bool deskew) {
  const Stopwatch total;
  ScanReport report;
  report.t_start_s = report.t_end_s = t_s;
  for (const ScanPoint& p : points) report.t_end_s = std::max(report.t_end_s, p.t_s);
  report.num_points = points.size();
  const Prediction prediction = Predict(t_s, deskew ? report.t_end_s : t_s);
  if (deskew) {
    const Stopwatch watch;
    MotionInterpolator motion(prediction.motion);
    for (ScanPoint& p : points) {
      bool outside = false;
      p.p_base = motion.Apply(p.t_s, p.p_base.cast<double>(), &outside).cast<float>();
      report.num_motion_extrapolated += outside ? 1 : 0;
    }
    report.imu_deskew = prediction.imu_motion;
    report.timings.deskew_ms = watch.ms();
  }
  ProcessCloud(t_s, std::move(points), prediction, &report);
  RecordMeasuredPose(t_s, report.t_end_s, deskew ? &prediction.motion : nullptr);
  report.timings.total_ms = total.ms();
  return report;
}

// preprocess -> features -> register -> fuse -> map, shared by all entries.
void Estimator::ProcessCloud(Seconds t_s, std::vector<ScanPoint> points, const Prediction& prediction,
                             ScanReport* report) {
  FeatureSet features = ExtractScanFeatures(t_s, std::move(points), report);
  const Eigen::Matrix3Xf unscreened_base = vacated_ ? RegistrationFeatures(features) : Eigen::Matrix3Xf();
  ScreenMovingFeatures(t_s, prediction.T_world_base, unscreened_base, &features, report);
  Matrix6d information_base = Matrix6d::Zero();
  const Pose3 T_world_base_lidar = Register(features, prediction.T_world_base, report, &information_base);
  const Pose3 T_world_base = Fuse(t_s, T_world_base_lidar, information_base, prediction, report);
  if (vacated_) vacated_->Remember(t_s, T_world_base, unscreened_base);
  UpdateMap(t_s, features, T_world_base, report);
  DropOldData(t_s);
}

// Rotary transform (encoder angle at each point's time), then the carrier's motion from the prediction's table.
std::vector<ScanPoint> Estimator::Deskew(const LidarScan& scan, const Prediction& prediction, ScanReport* report) {
  const Stopwatch watch;
  // The previous scan's preprocessed points are no longer needed (UpdateMap has run): their buffer is reused,
  // so only points beyond its size are value-initialised (a fresh 1 MB vector was a quarter of this stage).
  std::vector<ScanPoint> points = std::move(preprocessed_);
  preprocessed_.clear();
  const DeskewCounts counts = DeskewScan(rotor_, prediction.motion, scan, &points);
  report->num_rotor_fallback = counts.rotor_fallback;
  report->num_motion_extrapolated = counts.motion_extrapolated;
  report->imu_deskew = prediction.imu_motion;
  if (config_.keep_deskewed) {
    report->deskew_source = scan.points;
    report->deskewed_base.resize(points.size());
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (size_t i = 0; i < points.size(); ++i)
      report->deskewed_base[i] = points[i].p_base.allFinite() ? points[i].p_base : Eigen::Vector3f(nan, nan, nan);
  }
  report->timings.deskew_ms = watch.ms();
  return points;
}

// Preprocess (range gate, SOR) and the curvature features; the preprocessed points are kept for the dense map.
FeatureSet Estimator::ExtractScanFeatures(Seconds t_s, std::vector<ScanPoint> points, ScanReport* report) {
  Stopwatch watch;
  PreprocessResult pre = Preprocess(std::move(points), config_.preprocess);
  preprocessed_ = std::move(pre.points);
  report->num_registered = preprocessed_.size();
  report->timings.preprocess_ms = watch.ms();
  watch.Restart();
  FeatureResult result = ExtractFeatures(preprocessed_, t_s, config_.features);
  report->features = {result.stats.num_edge, result.stats.num_planar, result.stats.num_less_sharp,
                      result.stats.num_less_flat};
  report->timings.features_ms = watch.ms();
  return std::move(result.features);
}

// Moving objects out of registration: the scan-side features standing where earlier scans saw free space (a
// person walking into the view) are dropped before they are matched, judged at the predicted pose. The map side
// (less_sharp / less_flat) is judged again at the registered pose when it enters the local map (UpdateMap).
// Only with a prediction that holds: the window's IMU, or without the IMU the LiDAR-only velocity window. The last
// two scans' constant twist (before IMU initialisation, or lidar_only_velocity_window_s 0) can be off by more than
// the test's margin, and then the walls ahead look like free space: LiDAR-only parking 12 s, typical, seeds 1-5,
// 0.066 / 0.175 / 0.169 / 0.062 / 0.070 m unscreened, 0.062 / 0.080 / 3.64 / 0.072 / 0.719 m screened with it.
// With the velocity window the screen keeps the 40 s corridor's walker out (docs/registration.md).
// Objects moving with the rig are never arrivals (their earlier bodies hid their present places): the vacated
// screen first drops the features standing near places the recent scans' features left (VacatedScreen). It runs
// only on the IMU's prediction: with the LiDAR-only velocity window static features looked vacated (6-10 % of
// them on static recordings, against 1-2 % with the IMU) and LiDAR-only ATE rose by up to 37 %.
void Estimator::ScreenMovingFeatures(Seconds t_s, const Pose3& T_world_base_guess,
                                     const Eigen::Matrix3Xf& unscreened_base, FeatureSet* features,
                                     ScanReport* report) {
  const bool predicted = imu_initialized() || (!config_.use_imu && config_.lidar_only_velocity_window_s > 0);
  if (!free_space_ || !config_.free_space.screen_scan_features || !predicted) return;
  if (vacated_ && imu_initialized()) {  // the LiDAR-only prediction is too coarse for it (docs/estimator.md)
    std::vector<uint8_t> flagged;
    const RangeImage& image = free_space_->PrepareImage(preprocessed_);  // AddToDenseMap's AddScan takes it
    report->vacated_valve = vacated_->Flag(t_s, T_world_base_guess, image, unscreened_base, &flagged).valve;
    report->num_vacated_features = DropFlagged(flagged, {&features->edge, &features->planar});
  }
  report->num_moving_scan_features =
      report->num_vacated_features +
      DropSeenThrough(*free_space_, t_s, T_world_base_guess, {&features->edge, &features->planar});
}

size_t DropSeenThrough(const FreeSpaceFilter& filter, Seconds t_s, const Pose3& T_world_base,
                       std::initializer_list<pcl::PointCloud<pcl::PointXYZI>*> clouds) {
  size_t total = 0;
  for (const auto* cloud : clouds) total += cloud->size();
  Eigen::Matrix3Xf p_world(3, Eigen::Index(total));
  Eigen::Index col = 0;
  for (const auto* cloud : clouds)
    for (const pcl::PointXYZI& q : *cloud)
      p_world.col(col++) = (T_world_base * Eigen::Vector3d(q.x, q.y, q.z)).cast<float>();
  std::vector<uint8_t> seen;
  filter.SeenThroughBefore(t_s, p_world, &seen);
  return DropFlagged(seen, clouds);
}

size_t DropFlagged(const std::vector<uint8_t>& drop, std::initializer_list<pcl::PointCloud<pcl::PointXYZI>*> clouds) {
  size_t next = 0, dropped = 0;
  for (auto* cloud : clouds) {
    const size_t before = cloud->size();
    size_t kept = 0;
    for (size_t i = 0; i < before; ++i)
      if (!drop[next++]) cloud->points[kept++] = cloud->points[i];
    cloud->points.resize(kept);
    cloud->width = uint32_t(kept);
    cloud->height = 1;
    dropped += before - kept;
  }
  return dropped;
}

Eigen::Matrix3Xf RegistrationFeatures(const FeatureSet& features) {
  Eigen::Matrix3Xf p(3, Eigen::Index(features.edge.size() + features.planar.size()));
  Eigen::Index col = 0;
  for (const auto* cloud : {&features.edge, &features.planar})
    for (const pcl::PointXYZI& q : *cloud) p.col(col++) = q.getVector3fMap();
  return p;
}

}  // namespace rotolidar
